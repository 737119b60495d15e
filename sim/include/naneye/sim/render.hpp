#pragma once
// The in-memory renderer: a checkerboard at a pose seen by both cameras of a rig through the full
// model (recon::CameraModel), with the sensor of sensor.hpp, and the exact truth of every corner.
//
// Usage (the cheap path for many frames: the Renderer precomputes each camera's rays once, ~0.2 s):
//   naneye::sim::Renderer r(rig, scene, naneye::sim::SensorSettings{});
//   naneye::sim::Rng rng(42);
//   naneye::sim::RenderedPair p = r.render(pose, rng);   // p.left, p.right: CV_16UC1 250 x 250
// For an exact, noise-free and blur-free image use SensorSettings::ideal() (and scene.lighting =
// false for uniform shading). render_pair() is the one-call form (builds a Renderer each call).
//
// Conventions: pixel centres at integer coordinates (OpenCV); pixel (r, c) integrates the scene over
// [c - 0.5, c + 0.5] x [r - 0.5, r + 0.5]. Points of the image beyond the distortion model's fold get
// no light (undistort returns outside_model there): they read black level plus noise.
#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/sim/scene.hpp"
#include "naneye/sim/sensor.hpp"
#include "naneye/sim/sensor_model.hpp"

namespace naneye::sim {

enum class Eye : int { left = 0, right = 1 };

// Ground truth of one rendered pair. Corners are row-major over the inner grid (board rows first).
struct Truth {
  Pose pose;                                // board -> left camera
  std::vector<Eigen::Vector3d> corners_mm;  // left camera frame
  // Raw pixel coordinates from CameraModel::project; valid only where *_imaged is true (the corner
  // lies in front of the camera and inside the model's valid domain: otherwise the projection is a
  // folded-back number that no ray reaches).
  std::vector<Eigen::Vector2d> left_px, right_px;
  std::vector<bool> left_imaged, right_imaged;
  // Imaged and inside the active pixels (0 <= u <= 248, 0 <= v <= 249, minus the padding).
  std::vector<bool> left_in_view, right_in_view;
  bool board_present = true;
  bool board_in_view = true;  // board present and every inner corner in view in both images
};

struct RenderedPair {
  cv::Mat left, right;  // CV_16UC1, 250 x 250, 10-bit values, reference pixels and padding included
  Truth truth;
};

// One rendered image as the detector reads it (no copy: the view borrows `image`'s pixels).
recon::RawImageView raw_view(const cv::Mat& image, bool bayer = false);

// Corners of `board` at `pose`, projected by both cameras of `rig`.
Truth compute_truth(const recon::StereoRig& rig, const BoardGeometry& board, const Pose& pose,
                    bool board_present = true);

class Renderer {
 public:
  Renderer(const recon::StereoRig& rig, const SceneSettings& scene, const SensorSettings& sensor);

  const recon::StereoRig& rig() const { return rig_; }
  const SceneSettings& scene() const { return scene_; }
  const SensorSettings& sensor() const { return sensor_.settings(); }

  // Working images reused from frame to frame by render_into (one per rendering thread).
  struct Scratch {
    cv::Mat light;
    SensorModel::Scratch sensor;
    std::vector<int> cells;
    std::vector<float> board_part, background_part;
  };

  RenderedPair render(const Pose& board, Rng& rng) const;
  // The form for the live source: writes into 250 x 250 row-major buffers, reusing `scratch`, so a
  // steady stream of frames allocates nothing of its own.
  void render_into(const Pose& board, Rng& rng, std::uint16_t* left, std::uint16_t* right,
                   Scratch& scratch) const;
  // The same without any board (background only), whatever scene().board_present says.
  void render_background_into(Rng& rng, std::uint16_t* left, std::uint16_t* right, Scratch& scratch) const;
  // The light reaching each pixel before the sensor (CV_32FC1, 1.0 = a white square facing the
  // camera on axis at the light's reference distance): scene radiance integrated over the pixel,
  // with the lighting and, if the sensor has it, the vignetting. No blur, noise or quantisation.
  cv::Mat irradiance(Eye eye, const Pose& board) const;

 private:
  // Exact rays (CameraModel::undistort) where the renderer needs them, computed once per camera.
  struct RayTable {
    std::vector<double> corner;       // (250 + 1)^2 pixel corners, (x, y) normalized; NaN beyond the fold
    std::vector<float> centre;        // per pixel: its centre's ray (mean valid sub-sample ray at the fold)
    std::vector<float> cos4;          // per pixel: cos^4 of that ray's angle to the axis (0: no ray)
    std::vector<int> fold_pixels;     // pixels with a corner beyond (or too near) the fold ...
    std::vector<std::uint8_t> exact;  // per pixel: 1 for the fold pixels
    std::vector<float> fold_rays;     // ... and their sub-sample rays, kFoldSamplesPerSide^2 each, NaN beyond
  };
  struct Bilinear {
    double w00, w01, w10, w11;
  };
  static constexpr int kFoldSamplesPerSide = 8;
  static constexpr double kMaxInterpolationErrorPx = 5e-3;
  static RayTable build_rays(const recon::CameraModel& cam);
  void irradiance_into(Eye eye, const Pose& board, bool present, Scratch& scratch, float* out) const;

  recon::StereoRig rig_;
  SceneSettings scene_;
  SensorModel sensor_;
  RayTable rays_[2];
  std::vector<Bilinear> edge_weights_;  // edge sub-samples as weights of the pixel's corner rays
};

// One call: builds a Renderer (precomputing rays), renders one pair.
RenderedPair render_pair(const SceneSettings& scene, const SensorSettings& sensor,
                         const recon::StereoRig& rig, const Pose& board, Rng& rng);

}  // namespace naneye::sim
