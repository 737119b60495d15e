// Scene -> light on each pixel. Every sub-sample's ray comes from CameraModel::undistort (exact
// inverse of the paper's Eq. 5-6), precomputed once per camera; per frame the board plane maps those
// rays to board coordinates by one homography, where the checker pattern is evaluated analytically.
#include <spdlog/spdlog.h>

#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "naneye/driver/wire_format.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {
namespace {

constexpr int kSize = driver::kSensorSize;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// What one camera needs per frame: the homography from normalized rays to board coordinates and
// the light in this camera's frame.
struct View {
  Eigen::Matrix3d ray_to_board;  // (u, v, 1) ~ ray_to_board * (x, y, 1); third row > 0 in front
  Eigen::Vector3d normal;        // board normal in camera coordinates
  Eigen::Vector3d origin;        // board origin in camera coordinates
  Eigen::Vector3d light;         // light position in camera coordinates
};

View make_view(const recon::StereoRig& rig, Eye eye, const Pose& pose, const SceneSettings& scene) {
  Eigen::Matrix3d R = pose.R;
  Eigen::Vector3d t = pose.t, light = scene.light_mm;
  if (eye == Eye::right) {
    R = rig.R * pose.R;
    t = rig.R * pose.t + rig.T;
    light = rig.R * scene.light_mm + rig.T;
  }
  Eigen::Matrix3d M;
  M << R.col(0), R.col(1), t;  // board (u, v, 1) -> camera point, up to scale
  View v;
  // M (u, v, 1) = X = d (x, y, 1) gives M^-1 (x, y, 1) = (u, v, 1) / d: the third component is the
  // inverse depth of the ray's hit, positive exactly when the board is in front.
  v.ray_to_board = M.inverse();
  v.normal = R.col(2);
  v.origin = t;
  v.light = light;
  return v;
}

// Board pattern at board coordinates (u, v): reflectance, or a negative value off the board.
struct Pattern {
  double s, u0, u1, v0, v1, m, white, black;
  explicit Pattern(const SceneSettings& sc)
      : s(sc.board.square_mm),
        u0(-sc.board.square_mm),
        u1((sc.board.square_cols - 1) * sc.board.square_mm),
        v0(-sc.board.square_mm),
        v1((sc.board.square_rows - 1) * sc.board.square_mm),
        m(sc.board.border_squares * sc.board.square_mm),
        white(sc.white),
        black(sc.black) {}
  double operator()(double u, double v) const {
    if (u < u0 - m || u >= u1 + m || v < v0 - m || v >= v1 + m) return -1.0;
    if (u < u0 || u >= u1 || v < v0 || v >= v1) return white;
    const long a = static_cast<long>(std::floor(u / s)), b = static_cast<long>(std::floor(v / s));
    return ((a + b) & 1) == 0 ? black : white;  // the square below-right of the origin corner is black
  }
};

}  // namespace

Renderer::RayTable Renderer::build_rays(const recon::CameraModel& cam, int n) {
  RayTable t;
  t.n = n;
  const std::size_t pixels = static_cast<std::size_t>(kSize) * kSize;
  t.sub.resize(pixels * n * n * 2);
  t.centre.resize(pixels * 2);
  t.cos4.resize(pixels);
  for (int r = 0; r < kSize; ++r) {
    for (int c = 0; c < kSize; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * kSize + c;
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      int valid = 0;
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          // Sub-sample centres of an n x n split of [c - 0.5, c + 0.5] x [r - 0.5, r + 0.5].
          const Eigen::Vector2d px(c + (i + 0.5) / n - 0.5, r + (j + 0.5) / n - 0.5);
          const recon::Undistorted u = cam.undistort(px);
          float* out = &t.sub[(p * n * n + j * n + i) * 2];
          if (u.ok()) {
            out[0] = static_cast<float>(u.normalized.x());
            out[1] = static_cast<float>(u.normalized.y());
            sum += u.normalized;
            ++valid;
          } else {
            out[0] = out[1] = kNaN;
          }
        }
      }
      if (valid > 0) {
        const Eigen::Vector2d m = sum / valid;
        t.centre[p * 2] = static_cast<float>(m.x());
        t.centre[p * 2 + 1] = static_cast<float>(m.y());
        const double c2 = 1.0 / (1.0 + m.squaredNorm());  // cos^2 of the angle to the optical axis
        t.cos4[p] = static_cast<float>(c2 * c2);
      } else {
        t.centre[p * 2] = t.centre[p * 2 + 1] = kNaN;
        t.cos4[p] = 0.0f;
      }
    }
  }
  return t;
}

Renderer::Renderer(const recon::StereoRig& rig, const SceneSettings& scene, const SensorSettings& sensor)
    : rig_(rig), scene_(scene), sensor_(sensor) {
  if (scene_.supersample < 1 || scene_.supersample > 32)
    throw std::invalid_argument("sim: supersample must be in 1..32");
  if (rig.left.width() != kSize || rig.left.height() != kSize || rig.right.width() != kSize ||
      rig.right.height() != kSize)
    throw std::invalid_argument("sim: the rig's cameras must be 250 x 250 (NanEye 2D)");
  rays_[0] = build_rays(rig_.left, scene_.supersample);
  rays_[1] = build_rays(rig_.right, scene_.supersample);
  init_defects();
}

void Renderer::irradiance_into(Eye eye, const Pose& board, float* out) const {
  const RayTable& rt = rays_[static_cast<int>(eye)];
  const View view = make_view(rig_, eye, board, scene_);
  const Pattern pattern(scene_);
  const int nn = rt.n * rt.n;
  const double inv_nn = 1.0 / nn;
  const Eigen::Matrix3d& H = view.ray_to_board;
  const double ref2 = scene_.light_reference_mm * scene_.light_reference_mm;
  const bool present = scene_.board_present;
  for (int p = 0; p < kSize * kSize; ++p) {
    const float* s = &rt.sub[static_cast<std::size_t>(p) * nn * 2];
    double board_sum = 0.0;
    int background = 0;
    for (int k = 0; k < nn; ++k) {
      const double x = s[2 * k], y = s[2 * k + 1];
      if (std::isnan(x)) continue;  // beyond the fold: no ray, no light
      const double w = H(2, 0) * x + H(2, 1) * y + H(2, 2);
      double a = -1.0;
      if (present && w > 0.0) {
        const double iw = 1.0 / w;
        a = pattern((H(0, 0) * x + H(0, 1) * y + H(0, 2)) * iw, (H(1, 0) * x + H(1, 1) * y + H(1, 2)) * iw);
      }
      if (a < 0.0)
        ++background;
      else
        board_sum += a;
    }
    // Shading is smooth: evaluated once per pixel, on the mean ray of its valid sub-samples.
    double light = 1.0;
    const double cx = rt.centre[2 * p], cy = rt.centre[2 * p + 1];
    if (scene_.lighting && board_sum > 0.0) {
      const double w = H(2, 0) * cx + H(2, 1) * cy + H(2, 2);
      light = 0.0;
      if (w > 0.0) {
        const Eigen::Vector3d P = Eigen::Vector3d(cx, cy, 1.0) / w;  // the ray's point on the board plane
        const Eigen::Vector3d to_light = view.light - P;
        const double d2 = to_light.squaredNorm();
        // The lit side is the side the camera sees: orient the normal towards the camera.
        const Eigen::Vector3d n = view.normal.dot(-P) >= 0.0 ? view.normal : Eigen::Vector3d(-view.normal);
        const double cos_i = n.dot(to_light) / std::sqrt(d2);
        light = cos_i > 0.0 ? ref2 * cos_i / d2 : 0.0;
      }
    }
    double v = (board_sum * light + background * scene_.background) * inv_nn;
    if (sensor_.vignetting) v *= rt.cos4[p];
    out[p] = static_cast<float>(v);
  }
}

cv::Mat Renderer::irradiance(Eye eye, const Pose& board) const {
  cv::Mat m(kSize, kSize, CV_32FC1);
  irradiance_into(eye, board, m.ptr<float>());
  return m;
}

RenderedPair Renderer::render(const Pose& board, Rng& rng) const {
  RenderedPair out;
  out.left.create(kSize, kSize, CV_16UC1);
  out.right.create(kSize, kSize, CV_16UC1);
  Scratch scratch;
  render_into(board, rng, out.left.ptr<std::uint16_t>(), out.right.ptr<std::uint16_t>(), scratch);
  out.truth = compute_truth(rig_, scene_.board, board, scene_.board_present);
  return out;
}

void Renderer::render_into(const Pose& board, Rng& rng, std::uint16_t* left, std::uint16_t* right,
                           Scratch& scratch) const {
  scratch.light.create(kSize, kSize, CV_32FC1);
  irradiance_into(Eye::left, board, scratch.light.ptr<float>());
  sensor_into(Eye::left, scratch, rng, left);
  irradiance_into(Eye::right, board, scratch.light.ptr<float>());
  sensor_into(Eye::right, scratch, rng, right);
}

RenderedPair render_pair(const SceneSettings& scene, const SensorSettings& sensor,
                         const recon::StereoRig& rig, const Pose& board, Rng& rng) {
  return Renderer(rig, scene, sensor).render(board, rng);
}

}  // namespace naneye::sim
