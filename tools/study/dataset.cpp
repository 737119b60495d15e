// Rendering and detection of one dataset: the simulator's noisy renders of the paper's board at the
// preset's distances, corners found by the daemon's own detector (what a user of naneye gets).
#include <spdlog/spdlog.h>

#include <limits>
#include <memory>
#include <random>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/pair/opencv_path.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/sim/render.hpp"
#include "study.hpp"

namespace naneye::tools::study {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The detector numbers a 9 x 7 board up to a 180-degree turn (it looks the same turned): match its ids
// to the truth's by the left pixels, as they are or reversed.
bool ids_reversed(const recon::PairResult& r, const std::vector<Eigen::Vector2d>& truth_left) {
  const int n = static_cast<int>(truth_left.size());
  double direct = 0, reversed = 0;
  for (int i = 0; i < r.point_count; ++i) {
    const auto& p = r.points[static_cast<std::size_t>(i)];
    if (p.id < 0 || p.id >= n) continue;
    direct += (p.left_px - truth_left[static_cast<std::size_t>(p.id)]).norm();
    reversed += (p.left_px - truth_left[static_cast<std::size_t>(n - 1 - p.id)]).norm();
  }
  return reversed < direct;
}

// The OpenCV user path on the same pair, its ids matched to the truth's the same way.
void run_opencv(const Dataset& d, const cv::Mat& left, const cv::Mat& right, View& v) {
  recon::OpenCvPathSettings o;
  o.board = d.board;
  const recon::OpenCvPathResult r =
      recon::opencv_reconstruct_pair(d.rig, sim::raw_view(left), sim::raw_view(right), o);
  const std::size_t n = v.truth_left.size();
  v.opencv_left.assign(n, Eigen::Vector2d::Constant(kNaN));
  v.opencv_right = v.opencv_left;
  if (!r.found || r.left_px.size() != n) return;
  double direct = 0, reversed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p(r.left_px[i].x, r.left_px[i].y);
    direct += (p - v.truth_left[i]).norm();
    reversed += (p - v.truth_left[n - 1 - i]).norm();
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t id = reversed < direct ? n - 1 - i : i;
    v.opencv_left[id] = {r.left_px[i].x, r.left_px[i].y};
    v.opencv_right[id] = {r.right_px[i].x, r.right_px[i].y};
    v.points[opencv][id] = r.xyz_mm[i];
  }
  v.opencv_found = true;
}

}  // namespace

Dataset render_dataset(const sim::Preset& preset, int views, std::uint64_t seed) {
  Dataset d;
  d.preset = preset;
  d.rig = recon::load_rig(sim::find_calibration(preset.calib_file));
  const sim::SceneSettings scene = sim::preset_scene(preset);
  d.board = scene.board;
  const int n = scene.board.count();

  const sim::Renderer renderer(d.rig, scene, sim::SensorSettings{});
  recon::StereoReconstructorSettings rs;
  rs.corners.board = d.board;
  rs.tracking = false;  // every view is a separate photograph, as the paper's
  recon::StereoReconstructor reconstructor(d.rig, rs);
  auto result = std::make_unique<recon::PairResult>();

  sim::Rng rng(seed);
  sim::PoseSettings ps;
  ps.distance_mm = preset.distance_mm;
  for (int k = 0; k < views; ++k) {
    const sim::Pose pose = sim::sample_full_pose(d.rig, scene.board, ps, rng);
    const sim::RenderedPair img = renderer.render(pose, rng);
    View v;
    v.truth_mm = img.truth.corners_mm;
    v.truth_left = img.truth.left_px;
    v.truth_right = img.truth.right_px;
    v.left_px.assign(static_cast<std::size_t>(n), Eigen::Vector2d::Constant(kNaN));
    v.right_px = v.left_px;
    v.detected.assign(static_cast<std::size_t>(n), false);
    for (auto& p : v.points) p.assign(static_cast<std::size_t>(n), Eigen::Vector3d::Constant(kNaN));
    const auto outcome = reconstructor.process(sim::raw_view(img.left), sim::raw_view(img.right), *result);
    v.found = outcome == recon::PairOutcome::board_found && result->point_count == n;
    if (v.found) {
      const bool rev = ids_reversed(*result, v.truth_left);
      for (int i = 0; i < result->point_count; ++i) {
        const auto& p = result->points[static_cast<std::size_t>(i)];
        const auto id = static_cast<std::size_t>(rev ? n - 1 - p.id : p.id);
        v.left_px[id] = p.left_px;
        v.right_px[id] = p.right_px;
        v.detected[id] = true;
        if (p.valid) v.points[poly_tri][id] = p.xyz_mm;
        v.points[poly_board][id] = p.xyz_board_mm;
      }
      ++d.found;
    } else {
      spdlog::warn("study: {} view {}: no board ({})", preset.name, k, recon::to_string(outcome));
    }
    run_opencv(d, img.left, img.right, v);
    d.opencv_found += v.opencv_found;
    d.views.push_back(std::move(v));
  }
  return d;
}

}  // namespace naneye::tools::study
