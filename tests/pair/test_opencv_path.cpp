// The OpenCV reference path (opencv_path.hpp) on the bundled Dataset 3 capture, against its truth:
// it finds the whole boards, its 3D error is what an OpenCV user gets (several mm at ~70 mm), and our
// path (StereoReconstructor) does better on the very same pairs.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/pair/opencv_path.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"

using namespace naneye;

namespace {

namespace fs = std::filesystem;

recon::RawImageView view_of(const driver::Frame& f) {
  recon::RawImageView v;
  v.data = f.pixels.data();
  v.layout =
      f.color == driver::ColorMode::bayer_grbg ? recon::PixelLayout::bayer_grbg : recon::PixelLayout::mono;
  return v;
}

// Sum of squared 3D errors against the truth's corners, with the numbering as is or turned by
// 180 degrees, whichever fits (ids follow an image convention, the truth the board's own).
// Points with a NaN coordinate (not triangulated) are skipped; `count` gets the number used.
double best_sq_error(const std::vector<Eigen::Vector3d>& xyz, const nlohmann::json& truth_mm, int& count) {
  double as_is = 0, turned = 0;
  const std::size_t n = xyz.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!xyz[i].allFinite()) continue;
    ++count;
    auto t = [&](std::size_t k) {
      return Eigen::Vector3d(truth_mm[k][0].get<double>(), truth_mm[k][1].get<double>(),
                             truth_mm[k][2].get<double>());
    };
    as_is += (xyz[i] - t(i)).squaredNorm();
    turned += (xyz[i] - t(n - 1 - i)).squaredNorm();
  }
  return std::min(as_is, turned);
}

}  // namespace

TEST(OpenCvPath, BundledDataset3AgainstTruthAndOurs) {
  const fs::path dir = fs::path(NANEYE_TEST_DATA_DIR) / "sim-d3-mono";
  std::ifstream tf(dir / "truth.json");
  const nlohmann::json truth = nlohmann::json::parse(tf);
  const recon::StereoRig rig =
      recon::load_rig(fs::path(NANEYE_SOURCE_DIR) / "config/calib" / truth["calibration"].get<std::string>());
  auto src = driver::make_default_registry().open("file://" + (dir / "capture.raw").string() + "?speed=max");
  src->start();

  recon::StereoReconstructorSettings settings;
  settings.tracking = false;  // the capture's poses are independent
  recon::StereoReconstructor ours(rig, settings);
  recon::PairResult out;
  int in_view = 0, cv_found = 0, ours_found = 0, cv_false = 0, n_cv = 0, n_ours = 0, n_board = 0;
  double cv_sq = 0, ours_sq = 0, ours_board_sq = 0;
  std::size_t i = 0;
  while (auto p = src->next(std::chrono::milliseconds(5000))) {
    const nlohmann::json& t = truth["pairs"][i++];
    const bool whole = t["board_in_view"].get<bool>();
    in_view += whole;
    const recon::OpenCvPathResult cv =
        recon::opencv_reconstruct_pair(rig, view_of(p->left), view_of(p->right));
    const bool we_found =
        ours.process(view_of(p->left), view_of(p->right), out) == recon::PairOutcome::board_found;
    if (!whole) {
      cv_false += cv.found;
      continue;
    }
    if (cv.found) {
      ASSERT_EQ(cv.xyz_mm.size(), 48u);
      ++cv_found;
      cv_sq += best_sq_error(cv.xyz_mm, t["corners_xyz_mm"], n_cv);
    }
    if (!we_found) continue;
    ++ours_found;
    ASSERT_EQ(out.point_count, 48);
    std::vector<Eigen::Vector3d> tri(48, Eigen::Vector3d::Constant(NAN)), board(48);
    for (int k = 0; k < out.point_count; ++k) {
      const auto& pt = out.points[static_cast<std::size_t>(k)];
      if (pt.valid) tri[static_cast<std::size_t>(pt.id)] = pt.xyz_mm;
      board[static_cast<std::size_t>(pt.id)] = pt.xyz_board_mm;
    }
    ours_sq += best_sq_error(tri, t["corners_xyz_mm"], n_ours);
    ours_board_sq += best_sq_error(board, t["corners_xyz_mm"], n_board);
  }
  src->stop();
  ASSERT_EQ(i, truth["pairs"].size());
  ASSERT_GT(n_cv, 0);
  ASSERT_GT(n_ours, 0);
  const double cv_rms = std::sqrt(cv_sq / n_cv), ours_rms = std::sqrt(ours_sq / n_ours),
               board_rms = std::sqrt(ours_board_sq / n_board);
  std::printf(
      "%d whole boards: OpenCV path found %d, 3D RMS %.3f mm; ours found %d, triangulated %.3f mm "
      "(%d of %d corners), board pose %.4f mm\n",
      in_view, cv_found, cv_rms, ours_found, ours_rms, n_ours, n_board, board_rms);
  EXPECT_EQ(cv_false, 0);
  EXPECT_GE(cv_found, in_view - 1);
  EXPECT_GE(ours_found, in_view);
  // measurements.md: 6.2 mm 3D RMS for an OpenCV path at ~70 mm (0.20 px corners, DLT after default
  // undistortion); this one measures ~1.7 mm here (cornerSubPix on the float luminance). Loose, but
  // it must be met, and the millimetre scale is what the ~1 mm baseline gives at 0.1-0.2 px.
  EXPECT_LT(cv_rms, 6.0);
  EXPECT_GT(cv_rms, 0.5);
  EXPECT_LT(ours_rms, cv_rms / 2);
  EXPECT_LT(board_rms, cv_rms / 10);
}
