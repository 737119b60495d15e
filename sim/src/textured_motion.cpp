// The hand-held trajectory of the textured scenes (textured.hpp): a camera held over tissue or a
// part drifts slowly and smoothly; it does not orbit. Sums of slow sines, incommensurate periods.
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "naneye/sim/textured.hpp"

namespace naneye::sim {
namespace {
// Periods (s) of each degree of freedom: 4-13 s, pairwise incommensurate, so the motion at 62 fps
// moves a pixel or less per pair and does not repeat within a session.
constexpr double kPeriodX = 7.3, kPeriodY = 9.1, kPeriodZ = 11.7;
constexpr double kPeriodRx = 5.3, kPeriodRy = 6.7, kPeriodRz = 12.9, kPeriodWobble = 4.1;
constexpr double kSideShare = 0.06;   // of the scale: sideways and up-down amplitude
constexpr double kAlongShare = 0.10;  // of the scale: along the view
constexpr double kTurnDeg = 3.0;      // about each axis
}  // namespace

Pose handheld_camera_pose(double scale_mm, double t) {
  const double w = 2 * std::numbers::pi, deg = std::numbers::pi / 180;
  auto wave = [&](double period, double phase) { return std::sin(w * t / period + phase); };
  // A second, faster and smaller term on the sideways motion: a hand's tremor-free drift is not a
  // pure sine.
  const Eigen::Vector3d c(
      scale_mm * kSideShare * (0.8 * wave(kPeriodX, 0.4) + 0.2 * wave(kPeriodWobble, 1.9)),
      scale_mm * kSideShare * (0.8 * wave(kPeriodY, 2.1) + 0.2 * wave(kPeriodWobble * 1.37, 0.2)),
      scale_mm * kAlongShare * wave(kPeriodZ, 0.0));
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(kTurnDeg * deg * wave(kPeriodRx, 1.0), Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(kTurnDeg * deg * wave(kPeriodRy, 2.6), Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(kTurnDeg * deg * wave(kPeriodRz, 0.7), Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  Pose p;
  p.R = R;
  p.t = c;
  return p;
}

TexturedSceneSettings seen_from(const TexturedSceneSettings& scene, const Pose& camera) {
  // X_scene = R X_cam + c  =>  X_cam = R^T X_scene - R^T c; composed with the surface's own pose.
  TexturedSceneSettings out = scene;
  const Eigen::Matrix3d Rt = camera.R.transpose();
  out.surface.pose_R = Rt * scene.surface.pose_R;
  out.surface.pose_t = Rt * (scene.surface.pose_t - camera.t);
  return out;
}

}  // namespace naneye::sim
