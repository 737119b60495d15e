// The renderer puts the scene where the camera model says, keeps the fold dark, and is repeatable.
#include <gtest/gtest.h>
#include <cstdlib>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/presets.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {
namespace {

recon::StereoRig rig_of(const std::string& preset) {
  return recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib" / (preset + ".yaml"));
}

// Symmetric centroid check. Around an inner corner the checker pattern is point-symmetric (opposite
// quadrants share a colour, both edges are straight lines through it, up to the distortion's slight
// curvature), and pixel-area integration over a point-symmetric sample set keeps it so. With the
// corner on a pixel centre, pixel c + d and pixel c - d must then read the same. If the image were
// symmetric about c + delta instead, I(c + d) - I(c - d) = -2 grad I(c + d) . delta to first order:
// the least-squares delta is the corner's displacement in the image, zero whatever the gradient's
// accuracy when the render is right.
// `corner` must lie on a pixel centre or half-way between pixel centres, so that mirroring maps
// pixels to pixels: x -> 2c - x.
Eigen::Vector2d symmetry_offset(const cv::Mat& img, const Eigen::Vector2d& corner) {
  const int c2x = static_cast<int>(std::lround(2 * corner.x())),
            c2y = static_cast<int>(std::lround(2 * corner.y()));
  cv::Mat f;
  img.convertTo(f, CV_64F);
  auto I = [&](int x, int y) { return f.at<double>(y, x); };
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  constexpr int kHalf = 3;
  for (int y = c2y / 2 - kHalf; y <= c2y / 2 + kHalf; ++y)
    for (int x = c2x / 2 - kHalf; x <= c2x / 2 + kHalf; ++x) {
      if (2 * x == c2x && 2 * y == c2y) continue;
      const Eigen::Vector2d g(0.5 * (I(x + 1, y) - I(x - 1, y)), 0.5 * (I(x, y + 1) - I(x, y - 1)));
      const double diff = I(x, y) - I(c2x - x, c2y - y);
      A += 4.0 * g * g.transpose();
      b += -2.0 * g * diff;
    }
  return A.ldlt().solve(b);
}

// Moves the board so that inner corner k lands exactly at `target` (raw pixel) in `eye`, keeping
// its depth.
Pose place_corner(const recon::StereoRig& rig, const BoardGeometry& b, Pose pose, int k, Eye eye,
                  const Eigen::Vector2d& target) {
  const recon::CameraModel& cam = eye == Eye::left ? rig.left : rig.right;
  Eigen::Vector3d X = pose.R * b.corner(k) + pose.t;
  if (eye == Eye::right) X = rig.R * X + rig.T;
  const recon::Undistorted u = cam.undistort(target);
  EXPECT_TRUE(u.ok());
  const Eigen::Vector3d delta = Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0) * X.z() - X;
  pose.t += eye == Eye::right ? Eigen::Vector3d(rig.R.transpose() * delta) : delta;
  return pose;
}

TEST(Render, IdealRenderPutsEveryCornerWhereTheModelProjectsIt) {
  // For each preset, random poses; each time one inner corner of one eye is put on a pixel centre
  // (or a half-pixel), and the rendered image must be symmetric about exactly that point.
  for (const char* name : {"paper-d1", "paper-d2", "paper-d3"}) {
    const auto preset = *find_preset(name);
    const recon::StereoRig rig = rig_of(name);
    SceneSettings scene = preset_scene(preset);
    scene.lighting = false;  // the light's gradient is not symmetric
    const Renderer r(rig, scene, SensorSettings::ideal());
    PoseSettings ps;
    ps.distance_mm = preset.distance_mm;
    ps.margin_px = 10;
    Rng rng(11);
    double worst = 0;
    for (int trial = 0; trial < 6; ++trial) {
      const Pose sampled = sample_full_pose(rig, scene.board, ps, rng);
      const int k = static_cast<int>(rng() % scene.board.count());
      const Eye eye = trial % 2 == 0 ? Eye::left : Eye::right;
      const Truth t0 = compute_truth(rig, scene.board, sampled);
      const Eigen::Vector2d px0 = eye == Eye::left ? t0.left_px[k] : t0.right_px[k];
      const Eigen::Vector2d target = px0.array().round() + (trial % 4 == 1 ? 0.5 : 0.0);
      const Pose pose = place_corner(rig, scene.board, sampled, k, eye, target);
      const RenderedPair pair = r.render(pose, rng);
      const Eigen::Vector2d truth_px = eye == Eye::left ? pair.truth.left_px[k] : pair.truth.right_px[k];
      ASSERT_LT((truth_px - target).norm(), 1e-9);
      // The 10-bit output and the light before quantisation must both be symmetric.
      const Eigen::Vector2d delta = symmetry_offset(eye == Eye::left ? pair.left : pair.right, target);
      const Eigen::Vector2d delta_light = symmetry_offset(r.irradiance(eye, pose), target);
      EXPECT_LE(delta_light.norm(), 0.01) << name << " trial " << trial;
      worst = std::max(worst, delta.norm());
      EXPECT_LE(delta.norm(), 0.01) << name << " trial " << trial << " corner " << k << " at "
                                    << target.transpose() << " off by " << delta.transpose();
    }
    std::cerr << name << ": worst corner offset " << worst << " px\n";
  }
}

TEST(Render, SymmetryCheckSeesACornerMovedByAFewHundredthsOfAPixel) {
  // The check above has teeth: put the corner 0.04 px off the pixel centre and it must say so.
  const auto preset = *find_preset("paper-d3");
  const recon::StereoRig rig = rig_of("paper-d3");
  SceneSettings scene = preset_scene(preset);
  scene.lighting = false;
  const Renderer r(rig, scene, SensorSettings::ideal());
  PoseSettings ps;
  ps.distance_mm = preset.distance_mm;
  ps.margin_px = 10;
  Rng rng(5);
  const Pose sampled = sample_full_pose(rig, scene.board, ps, rng);
  const Truth t0 = compute_truth(rig, scene.board, sampled);
  const Eigen::Vector2d centre = t0.left_px[20].array().round();
  const Eigen::Vector2d moved(0.04, -0.03);
  const Pose pose = place_corner(rig, scene.board, sampled, 20, Eye::left, centre + moved);
  const Eigen::Vector2d delta = symmetry_offset(r.irradiance(Eye::left, pose), centre);
  // The finite-difference gradient scales the estimate (~25 % on a blur-free image); the direction
  // and the size must still be those of the move, far outside the 0.01 px bar.
  EXPECT_LT((delta - moved).norm(), 0.4 * moved.norm()) << delta.transpose();
  EXPECT_GT(delta.norm(), 0.02);
}

TEST(Render, NothingBeyondTheFoldIsLit) {
  // Dataset 3's left camera folds at ~138.6 px from its principal point: 11.7 % of the image lies
  // beyond, where no ray exists. A board filling the view must leave all of it at black level.
  const recon::StereoRig rig = rig_of("paper-d3");
  SceneSettings scene;
  scene.board.square_mm = 40;  // a huge board: every valid pixel sees the board or its border
  scene.lighting = false;
  SensorSettings sensor = SensorSettings::ideal();
  const Renderer r(rig, scene, sensor);
  Pose pose;
  pose.t = Eigen::Vector3d(0, 0, 30) - scene.board.centre();
  Rng rng(1);
  const RenderedPair pair = r.render(pose, rng);
  const auto& cam = rig.left;
  int beyond = 0, lit_beyond = 0, inside = 0, dark_inside = 0;
  for (int y = 1; y < 249; ++y)
    for (int x = 4; x < 248; ++x) {
      // A pixel wholly beyond the fold: its four corners (and so all of it) have no ray.
      bool any_valid = false, all_valid = true;
      for (double dy : {-0.5, 0.5})
        for (double dx : {-0.5, 0.5}) {
          const bool ok = cam.undistort(Eigen::Vector2d(x + dx, y + dy)).ok();
          any_valid = any_valid || ok;
          all_valid = all_valid && ok;
        }
      const int v = pair.left.at<std::uint16_t>(y, x);
      if (!any_valid) {
        ++beyond;
        lit_beyond += v != static_cast<int>(sensor.black_level_dn);
      } else if (all_valid) {
        ++inside;
        dark_inside += v <= static_cast<int>(sensor.black_level_dn) + 10;
      }
    }
  EXPECT_GT(beyond, 4000);  // the fold really cuts the image corners
  EXPECT_EQ(lit_beyond, 0);
  EXPECT_EQ(dark_inside, 0);  // and every pixel inside sees the (lit) board
  EXPECT_GT(inside, 45000);
}

}  // namespace
}  // namespace naneye::sim
