#pragma once
// Textured scenes with analytic ground truth: a plane, a sphere, a tube seen from inside
// and a height field, covered with a band-limited, non-periodic solid texture, lit by a point light
// at the camera (cos(incidence) / d^2), rendered through the exact rig model (recon::CameraModel)
// to raw left/right frames. Truth: the left camera's per-pixel depth where both eyes see the surface.
// Units: mm; the left camera's frame is the world (docs/scene.md).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/sim/render.hpp"
#include "naneye/sim/sensor.hpp"
#include "naneye/sim/sensor_model.hpp"

namespace naneye::sim {

enum class SurfaceKind { plane, sphere, tube, height_field };

const char* to_string(SurfaceKind k);

// One analytic surface in the left camera's frame.
struct Surface {
  SurfaceKind kind = SurfaceKind::plane;
  // plane: a point and the unit normal; sphere: centre and radius; tube: a point on the axis, the
  // unit axis and the radius (the camera sits inside); height field: Z = origin.z() + h(X, Y).
  Eigen::Vector3d origin{0, 0, 30};
  Eigen::Vector3d axis{0, 0, 1};
  double radius_mm = 10;
  // Height field h(X, Y) = sum_i amp_i sin(kx_i X + ky_i Y + phase_i) (mm, rad/mm).
  struct Wave {
    double amp_mm, kx, ky, phase;
  };
  std::vector<Wave> waves;
  // Nearest and farthest depth a ray may meet it at (ray marching bounds of the height field).
  double z_min_mm = 1, z_max_mm = 500;
  // Where the surface sits: X_camera = pose.R X_surface + pose.t, the fields above being in the
  // surface's own frame (identity: they are in the left camera's frame). A moving camera moves this
  // pose; the texture (a function of the surface-frame point) moves with the surface.
  Eigen::Matrix3d pose_R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d pose_t = Eigen::Vector3d::Zero();

  // The first hit of the ray o + t d (t > 1e-9), camera frame, or empty.
  std::optional<double> intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  // Unit normal at a surface point, camera frame (sign irrelevant: shading uses |cos|).
  Eigen::Vector3d normal(const Eigen::Vector3d& X) const;
  // A camera-frame point in the surface's own frame (where the texture is defined).
  Eigen::Vector3d to_local(const Eigen::Vector3d& X) const { return pose_R.transpose() * (X - pose_t); }

 private:
  std::optional<double> intersect_local(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  Eigen::Vector3d normal_local(const Eigen::Vector3d& X) const;
};

// Solid texture: reflectance(X) = mean + contrast * sum_k cos(2 pi f_k . X + phi_k) / sqrt(K / 2),
// K random directions with |f_k| uniform in [1 / wavelength_max, 1 / wavelength_min] (cycles/mm):
// band-limited (no energy above 1 / wavelength_min) and, with incommensurate random frequencies,
// not periodic. Clamped to [0.02, 1].
struct TextureSettings {
  double wavelength_min_mm = 0.3, wavelength_max_mm = 1.5;
  int components = 32;
  double mean = 0.5, contrast = 0.17;
  std::uint64_t seed = 7;
};

struct TexturedSceneSettings {
  Surface surface;
  TextureSettings texture;
  // The light at the camera (the module's LED beside the lenses): irradiance cos(incidence) / d^2,
  // 1.0 for a surface facing it at light_reference_mm.
  Eigen::Vector3d light_mm{0.6, -0.9, 0.0};
  double light_reference_mm = 20;
};

struct TexturedPair {
  cv::Mat left, right;  // CV_16UC1 raw frames as the sensor delivers them
  // CV_64FC1, left raw grid: Z (mm) of the surface at the pixel centre where both eyes see it
  // (the right eye's view of that point is unoccluded, inside its image and its model's domain);
  // NaN elsewhere.
  cv::Mat depth;
};

class TexturedRenderer {
 public:
  // supersample: sub-samples per pixel side (pixel integration; 3 x 3 keeps the presets' shortest
  // texture wavelength, ~4 px, from aliasing). Precomputes every sub-sample's exact ray (~0.1 s).
  TexturedRenderer(const recon::StereoRig& rig, const SensorSettings& sensor, int supersample = 3);

  const recon::StereoRig& rig() const { return rig_; }
  TexturedPair render(const TexturedSceneSettings& scene, Rng& rng) const;
  // The frames alone (no truth: a live source needs none), the texture evaluated in single
  // precision (within 1e-5 of render()'s reflectance, a hundredth of a 10-bit step; ~3x faster).
  void render_frames(const TexturedSceneSettings& scene, Rng& rng, cv::Mat& left, cv::Mat& right) const;
  // The truth alone (no image).
  cv::Mat truth_depth(const Surface& s) const;
  // Z of the surface seen at a left raw pixel (any sub-pixel position) if both eyes see it.
  std::optional<double> truth_depth_at(const Surface& s, const Eigen::Vector2d& left_px) const;

 private:
  struct Rays {
    std::vector<float> sub;     // per pixel, n^2 sub-sample rays (x, y) normalized; NaN beyond the fold
    std::vector<float> centre;  // per pixel centre ray; NaN beyond the fold
    std::vector<float> cos4;    // per pixel: cos^4 of the centre ray's angle to the axis
  };
  Rays build(const recon::CameraModel& cam) const;
  // fast: the texture in single precision with a polynomial cosine (render_frames).
  void irradiance(int eye, const TexturedSceneSettings& scene, cv::Mat& out, bool fast = false) const;
  void expose(int eye, const cv::Mat& light, Rng& rng, cv::Mat& out) const;
  bool right_sees(const Surface& s, const Eigen::Vector3d& X) const;

  recon::StereoRig rig_;
  SensorModel sensor_;
  int n_;
  Rays rays_[2];
};

// The scenes (8-80 mm): "plane" (tilted 30 deg, 13-41 mm), "plane-far" (45-71 mm), "sphere"
// (12-20 mm), "tube" (radius 7 mm seen from inside, 8-80 mm along it, closed at 80 mm), "height" (a
// height field of three waves, 0.2-0.8 mm high, 4-8 mm long, around 15 mm). Texture scaled to
// each scene's depth (wavelengths ~4-20 px). Empty for an unknown name.
std::optional<TexturedSceneSettings> textured_preset(const std::string& name);
const std::vector<std::string>& textured_preset_names();
// The k-th render (k = 0, 1, ...) of a preset in the scene benchmarks and the tests that quote
// their figures: the texture seed moved by 100 k, the noise seeded 1000 + k. One rule, so that a
// test's figures, bench_scene's and bench_scene_limits' are of the same pairs.
TexturedPair numbered_render(const TexturedRenderer& renderer, const std::string& preset, int k);

// A smooth hand-held trajectory: the camera drifting slowly around where the preset puts it (sums
// of slow sines with incommensurate periods of 4-13 s, so it never repeats exactly): sideways and
// up-down by 6 % of `scale_mm`, along the view by 10 %, turning by up to 3 deg about each axis.
// Returns the camera's pose in the scene's frame at time t (s): X_scene = R X_camera + t.
Pose handheld_camera_pose(double scale_mm, double t_s);
// The scene as the camera at `camera` (in the scene's frame, handheld_camera_pose) sees it.
TexturedSceneSettings seen_from(const TexturedSceneSettings& scene, const Pose& camera);

}  // namespace naneye::sim

namespace naneye::sim {

// A capture of textured scenes in the spec's byte stream (capture.raw), one pair per scene, with
// the same free-running clocks as write_capture(); returns the truth depth of every pair. Bayer
// renders are read back with `?color=grbg`.
std::vector<cv::Mat> write_textured_capture(const std::filesystem::path& raw_file, const TexturedRenderer& r,
                                            const std::vector<TexturedSceneSettings>& scenes,
                                            std::uint64_t seed);

}  // namespace naneye::sim
