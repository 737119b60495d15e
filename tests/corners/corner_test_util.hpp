#pragma once
// Shared helpers of the corner tests: the simulator's renderer for the paper's Dataset 3 rig, random
// board poses of the Dataset 3 kind, and truth comparisons.
#include <Eigen/Geometry>
#include <filesystem>
#include <map>
#include <memory>
#include <random>

#include "../support/paper_rig.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::test {

enum class Scene { board, no_board, small_board };

// One Renderer per (sensor, scene): building one precomputes the rays (~0.2 s).
inline const sim::Renderer& renderer(bool bayer, Scene scene = Scene::board) {
  static std::map<std::pair<bool, Scene>, std::unique_ptr<sim::Renderer>> cache;
  auto& r = cache[{bayer, scene}];
  if (!r) {
    sim::SceneSettings s;
    s.board_present = scene != Scene::no_board;
    if (scene == Scene::small_board) {  // 8 x 6 squares: 7 x 5 inner corners
      s.board.rows = 5;
      s.board.cols = 7;
    }
    sim::SensorSettings sensor;
    sensor.bayer = bayer;
    r = std::make_unique<sim::Renderer>(paper_d3(), s, sensor);
  }
  return *r;
}

inline sim::RenderedPair render(bool bayer, const sim::Pose& pose, std::uint64_t seed,
                                Scene scene = Scene::board) {
  sim::Rng rng(seed);
  return renderer(bayer, scene).render(pose, rng);
}

// Every inner corner imaged and at least `margin` pixels inside the usable area (columns 0..248,
// rows 1..248): the corners a saddle fit can see whole.
inline bool fully_in_view(const std::vector<Eigen::Vector2d>& px, const std::vector<bool>& imaged,
                          double margin = 4.0) {
  for (std::size_t k = 0; k < px.size(); ++k) {
    const auto& p = px[k];
    if (!imaged[k] || p.x() < margin || p.x() > 248 - margin || p.y() < 1 + margin || p.y() > 248 - margin) {
      return false;
    }
  }
  return true;
}

// A random pose of the paper's Dataset 3 kind: grid centre at z_lo..z_hi mm, tilt up to max_tilt
// degrees about an axis in the board plane, an in-plane turn up to +-20 degrees, grid centre within
// max_offset_mm of the optical axis.
inline sim::Pose random_pose(std::mt19937_64& rng, double z_lo = 58, double z_hi = 85,
                             double max_tilt_deg = 40, double max_offset_mm = 4) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double kPi = 3.14159265358979323846;
  const double z = z_lo + (z_hi - z_lo) * U(rng);
  const double tilt = max_tilt_deg * kPi / 180 * std::sqrt(U(rng));
  const double axis_angle = 2 * kPi * U(rng);
  const double spin = (U(rng) - 0.5) * 40 * kPi / 180;
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis_angle), std::sin(axis_angle), 0)) *
       Eigen::AngleAxisd(spin, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  const Eigen::Vector3d centre_board = sim::BoardGeometry{}.centre();
  const Eigen::Vector3d centre_cam((U(rng) - 0.5) * 2 * max_offset_mm, (U(rng) - 0.5) * 2 * max_offset_mm, z);
  sim::Pose p;
  p.R = R;
  p.t = centre_cam - R * centre_board;
  return p;
}

// Largest distance between detected corners and the truth, with the numbering taken as is
// (turned = false) or turned by 180 degrees.
inline double max_error(const recon::CornerResult& res, const std::vector<Eigen::Vector2d>& truth,
                        bool turned) {
  double worst = 0;
  for (int i = 0; i < res.count; ++i) {
    const auto& t = truth[static_cast<std::size_t>(turned ? res.count - 1 - i : i)];
    worst = std::max(worst, (res.corners[static_cast<std::size_t>(i)].px - t).norm());
  }
  return worst;
}

// The numbering (as is or turned) that matches the truth best.
inline bool best_turn(const recon::CornerResult& res, const std::vector<Eigen::Vector2d>& truth) {
  return max_error(res, truth, true) < max_error(res, truth, false);
}

}  // namespace naneye::test
