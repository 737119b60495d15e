// Detection rate and accuracy of the corner detector on noisy renders of the paper's Dataset 3 setup.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "naneye/recon/calibration_io.hpp"
#include "naneye/recon/corners.hpp"
#include "render.hpp"

namespace naneye::recon {
namespace {

StereoRig paper_d3() {
  return load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
}

RawImageView view_of(const test::Rendered& r, bool bayer) {
  RawImageView v;
  v.data = r.pixels.data();
  v.layout = bayer ? PixelLayout::bayer_grbg : PixelLayout::mono;
  return v;
}

struct Stats {
  int frames = 0, in_view = 0, found = 0, false_found = 0;
  double sum2 = 0, worst = 0;
  int n = 0;
  double rms() const { return n ? std::sqrt(sum2 / n) : 0.0; }
};

Stats run_poses(bool bayer, int count, std::uint64_t seed) {
  const StereoRig rig = paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 rng(seed);
  Stats st;
  for (int k = 0; k < count; ++k) {
    test::RenderSpec spec;
    spec.pose = test::random_pose(rng);
    spec.bayer = bayer;
    spec.seed = seed * 1000 + static_cast<std::uint64_t>(k);
    const test::Rendered img = test::render_board(rig.left, spec);
    CornerResult res;
    det.detect_full(view_of(img, bayer), res);
    ++st.frames;
    if (img.all_in_view) ++st.in_view;
    if (!res.found) continue;
    ++st.found;
    // Ids up to the board's 180-degree symmetry: compare with the truth in either order.
    double e_direct = 0, e_flip = 0;
    for (int i = 0; i < res.count; ++i) {
      e_direct += (res.corners[i].px - img.truth[static_cast<std::size_t>(i)]).squaredNorm();
      e_flip += (res.corners[i].px - img.truth[static_cast<std::size_t>(res.count - 1 - i)]).squaredNorm();
    }
    const bool flip = e_flip < e_direct;
    for (int i = 0; i < res.count; ++i) {
      const auto& t = img.truth[static_cast<std::size_t>(flip ? res.count - 1 - i : i)];
      const double e = (res.corners[i].px - t).norm();
      st.sum2 += e * e;
      st.worst = std::max(st.worst, e);
      ++st.n;
      if (e > 1.0) ++st.false_found;
    }
  }
  std::printf("%s: %d frames, %d all in view, %d found, RMS %.4f px, worst %.4f px, corners off > 1 px: %d\n",
              bayer ? "bayer" : "mono", st.frames, st.in_view, st.found, st.rms(), st.worst, st.false_found);
  return st;
}

TEST(CornerAccuracy, MonoDataset3) {
  const Stats st = run_poses(false, 24, 3);
  EXPECT_EQ(st.found, st.in_view);
  EXPECT_EQ(st.false_found, 0);
  EXPECT_LE(st.rms(), 0.05);
  EXPECT_LE(st.worst, 0.25);
}

TEST(CornerAccuracy, BayerDataset3) {
  const Stats st = run_poses(true, 24, 5);
  EXPECT_EQ(st.found, st.in_view);
  EXPECT_EQ(st.false_found, 0);
  EXPECT_LE(st.rms(), 0.05);
  EXPECT_LE(st.worst, 0.25);
}

}  // namespace
}  // namespace naneye::recon
