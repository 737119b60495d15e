#pragma once
// Shared helpers of the calibration tests: board views of a known rig (the paper's Dataset 3
// calibration), either exact projections with white Gaussian corner noise of a known sigma, or
// rendered images run through the corner detector.
#include <filesystem>
#include <random>
#include <vector>

#include "../support/paper_rig.hpp"
#include "naneye/recon/calibrate/calibrate.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/presets.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::test {

inline recon::BoardGeometry recon_board() {
  return {6, 8, 5.99};
}

// Random full-board poses of the Dataset 3 kind (~70 mm, tilts up to 40 degrees).
inline std::vector<sim::Pose> sample_poses(const recon::StereoRig& rig, int count, std::uint64_t seed) {
  sim::Rng rng(seed);
  sim::PoseSettings ps;
  ps.distance_mm = 70;
  std::vector<sim::Pose> poses;
  for (int i = 0; i < count; ++i) poses.push_back(sim::sample_full_pose(rig, sim::BoardGeometry{}, ps, rng));
  return poses;
}

// Exact projections of every corner plus N(0, sigma_px^2) per coordinate.
inline std::vector<recon::CalibrationView> noisy_views(const recon::StereoRig& rig,
                                                       const std::vector<sim::Pose>& poses, double sigma_px,
                                                       std::uint64_t seed) {
  sim::Rng rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_px);
  const sim::BoardGeometry board;
  std::vector<recon::CalibrationView> views;
  for (const auto& pose : poses) {
    const sim::Truth t = sim::compute_truth(rig, board, pose);
    recon::CalibrationView v;
    for (int k = 0; k < board.count(); ++k) {
      const int row = k / board.cols, col = k % board.cols;
      const auto k_ = static_cast<std::size_t>(k);
      if (t.left_in_view[k_])
        v.left.push_back({row, col, t.left_px[k_] + Eigen::Vector2d(noise(rng), noise(rng))});
      if (t.right_in_view[k_])
        v.right.push_back({row, col, t.right_px[k_] + Eigen::Vector2d(noise(rng), noise(rng))});
    }
    views.push_back(std::move(v));
  }
  return views;
}

}  // namespace naneye::test
