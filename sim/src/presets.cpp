// Presets of the paper's datasets and rejection sampling of board poses that the cameras see whole.
#include "naneye/sim/presets.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace naneye::sim {

const std::vector<Preset>& presets() {
  static const std::vector<Preset> kPresets{
      {"paper-d1", "paper-d1.yaml", 2.25, 20.0},
      {"paper-d2", "paper-d2.yaml", 4.50, 50.0},
      {"paper-d3", "paper-d3.yaml", 5.99, 70.0},
  };
  return kPresets;
}

std::optional<Preset> find_preset(std::string_view name) {
  for (const auto& p : presets())
    if (p.name == name) return p;
  return std::nullopt;
}

std::filesystem::path find_calibration(const std::string& file) {
  const std::filesystem::path dirs[] = {NANEYE_SIM_INSTALL_CALIB_DIR, NANEYE_SIM_SOURCE_CALIB_DIR,
                                        "config/calib"};
  for (const auto& d : dirs)
    if (std::filesystem::exists(d / file)) return d / file;
  throw std::runtime_error("sim: calibration " + file + " not found (looked in " + dirs[0].string() + ", " +
                           dirs[1].string() + ", ./config/calib)");
}

SceneSettings preset_scene(const Preset& p) {
  SceneSettings s;
  s.board.square_mm = p.square_mm;
  s.light_reference_mm = p.distance_mm;
  return s;
}

bool pose_fully_visible(const recon::StereoRig& rig, const BoardGeometry& board, const Pose& pose,
                        const PoseSettings& s) {
  const Truth t = compute_truth(rig, board, pose);
  const double lo = s.margin_px, hi = 247.0 - s.margin_px;  // last active column is 248
  for (int k = 0; k < board.count(); ++k) {
    if (!t.left_imaged[k] || !t.right_imaged[k]) return false;
    for (const auto* px : {&t.left_px[k], &t.right_px[k]})
      if (px->x() < lo || px->x() > hi || px->y() < lo || px->y() > hi) return false;
    const Eigen::Vector3d Xr = rig.R * t.corners_mm[k] + rig.T;
    for (auto [cam, X] : {std::pair{&rig.left, t.corners_mm[k]}, std::pair{&rig.right, Xr}}) {
      const auto fold = cam->fold_radius_undistorted();
      if (fold && (X.head<2>() / X.z()).norm() > s.fold_margin * *fold) return false;
    }
  }
  return true;
}

namespace {

Pose random_pose(const BoardGeometry& board, const PoseSettings& s, double tilt_scale, Rng& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double deg = M_PI / 180.0;
  const double z = s.distance_mm * (s.distance_min + (s.distance_max - s.distance_min) * u01(rng));
  // Tilt: uniform in the cosine of the angle up to the maximum, about a random in-plane axis.
  const double cmin = std::cos(tilt_scale * s.max_tilt_deg * deg);
  const double tilt = std::acos(1.0 - (1.0 - cmin) * u01(rng));
  const double axis = 2.0 * M_PI * u01(rng);
  const double roll = (2.0 * u01(rng) - 1.0) * s.max_roll_deg * deg;
  Pose p;
  p.R = (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis), std::sin(axis), 0.0)) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
  const Eigen::Vector3d c(z * s.max_offset * (2.0 * u01(rng) - 1.0),
                          z * s.max_offset * (2.0 * u01(rng) - 1.0), z);
  p.t = c - p.R * board.centre();
  return p;
}

}  // namespace

Pose sample_full_pose(const recon::StereoRig& rig, const BoardGeometry& board, const PoseSettings& s,
                      Rng& rng) {
  // Steep tilts of a near board often push corners out of view: relax the tilt bit by bit rather
  // than loop for ever on a rig that cannot see the board at this distance.
  for (int attempt = 0; attempt < 2000; ++attempt) {
    const double tilt_scale = 1.0 - 0.5 * (attempt / 2000.0);
    Pose p = random_pose(board, s, tilt_scale, rng);
    if (pose_fully_visible(rig, board, p, s)) return p;
  }
  throw std::runtime_error("sim: no board pose keeps every inner corner in view at this distance");
}

Pose sample_partial_pose(const recon::StereoRig& rig, const BoardGeometry& board, const PoseSettings& s,
                         Rng& rng) {
  Pose p = sample_full_pose(rig, board, s, rng);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double dir = 2.0 * M_PI * u01(rng);
  const Eigen::Vector3d step =
      0.02 * p.t.z() * Eigen::Vector3d(std::cos(dir), std::sin(dir), 0.0);  // ~4 px per step at the centre
  // Slide until at least a fifth of the corners have left one image, but some remain in both.
  const int n = board.count();
  for (int i = 0; i < 200; ++i) {
    p.t += step;
    const Truth t = compute_truth(rig, board, p);
    int both = 0, missing = 0;
    for (int k = 0; k < n; ++k) {
      both += t.left_in_view[k] && t.right_in_view[k];
      missing += !(t.left_in_view[k] && t.right_in_view[k]);
    }
    if (missing >= n / 5) {
      if (both == 0) p.t -= 0.5 * step;  // overshot: come back half a step
      return p;
    }
  }
  return p;
}

}  // namespace naneye::sim
