// Scene -> light on each pixel. Every sub-sample's ray comes from CameraModel::undistort (exact
// inverse of the paper's Eq. 5-6), precomputed once per camera; per frame the board plane maps those
// rays to board coordinates by one homography, where the checker pattern is evaluated analytically.
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <numeric>

#include "naneye/driver/wire_format.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {
namespace {

using driver::kSensorSize;
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
        u1(sc.board.cols * sc.board.square_mm),
        v0(-sc.board.square_mm),
        v1(sc.board.rows * sc.board.square_mm),
        m(sc.border_squares * sc.board.square_mm),
        white(sc.white),
        black(sc.black) {}
  double operator()(double u, double v) const {
    if (u < u0 - m || u >= u1 + m || v < v0 - m || v >= v1 + m) return -1.0;
    if (u < u0 || u >= u1 || v < v0 || v >= v1) return white;
    const long a = static_cast<long>(std::floor(u / s)), b = static_cast<long>(std::floor(v / s));
    return ((a + b) & 1) == 0 ? black : white;  // the square below-right of the origin corner is black
  }
  // Which convex region (u, v) lies in: the background, the white border, or one square. A pixel
  // whose four corners share a convex region lies wholly inside it (the map is smooth at pixel scale).
  static constexpr int kBackground = -2, kBorder = -1;
  int cell(double u, double v) const {
    if (u < u0 - m || u >= u1 + m || v < v0 - m || v >= v1 + m) return kBackground;
    if (u < u0 || u >= u1 || v < v0 || v >= v1) return kBorder;
    return static_cast<int>(std::floor(u / s) + 2) * 1024 + static_cast<int>(std::floor(v / s) + 2);
  }
};

// Where a pixel's N = n^2 sub-samples sit: a rank-1 lattice ((k + 1/2) / N, ((g k + s) mod N + 1/2) / N)
// over the pixel. Unlike an n x n grid, every sample has its own column and row, so an edge near
// the pixel axes is resolved to 1/N of a pixel rather than 1/n; s = (g - 1) / 2 makes the set
// point-symmetric about the pixel centre, so a symmetric scene stays symmetric in the image.
std::vector<Eigen::Vector2d> sample_offsets(int n) {
  const int N = n * n;
  int best_g = 1;
  double best = -1;
  for (int g = 1; g < N; g += 2) {
    if (std::gcd(g, N) != 1) continue;
    double dmin = 1e9;  // shortest lattice vector on the torus
    for (int k = 1; k < N; ++k) {
      double dx = static_cast<double>(k) / N, dy = static_cast<double>((g * k) % N) / N;
      dx = std::min(dx, 1 - dx);
      dy = std::min(dy, 1 - dy);
      dmin = std::min(dmin, std::hypot(dx, dy));
    }
    if (dmin > best + 1e-12) best = dmin, best_g = g;
  }
  std::vector<Eigen::Vector2d> o(N);
  if (N == 1) return {Eigen::Vector2d::Zero()};
  const int s = (best_g - 1) / 2;
  for (int k = 0; k < N; ++k)
    o[k] = Eigen::Vector2d((k + 0.5) / N - 0.5, (((best_g * k + s) % N) + 0.5) / N - 0.5);
  return o;
}

}  // namespace

Renderer::RayTable Renderer::build_rays(const recon::CameraModel& cam) {
  RayTable t;
  constexpr int kc = kSensorSize + 1;
  t.corner.resize(static_cast<std::size_t>(kc) * kc * 2);
  for (int r = 0; r < kc; ++r)
    for (int c = 0; c < kc; ++c) {
      const recon::Undistorted u = cam.undistort(Eigen::Vector2d(c - 0.5, r - 0.5));
      double* out = &t.corner[(static_cast<std::size_t>(r) * kc + c) * 2];
      out[0] = u.ok() ? u.normalized.x() : std::numeric_limits<double>::quiet_NaN();
      out[1] = u.ok() ? u.normalized.y() : std::numeric_limits<double>::quiet_NaN();
    }
  const std::size_t pixels = static_cast<std::size_t>(kSensorSize) * kSensorSize;
  t.centre.resize(pixels * 2);
  t.cos4.resize(pixels);
  t.exact.assign(pixels, 0);
  const std::vector<Eigen::Vector2d> fold_offsets = sample_offsets(kFoldSamplesPerSide);
  for (int r = 0; r < kSensorSize; ++r) {
    for (int c = 0; c < kSensorSize; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * kSensorSize + c;
      const std::size_t k00 = static_cast<std::size_t>(r) * kc + c;
      bool all_valid = true;
      for (std::size_t k : {k00, k00 + 1, k00 + kc, k00 + kc + 1})
        all_valid = all_valid && !std::isnan(t.corner[2 * k]);
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      int valid = 0;
      if (all_valid) {
        // Next to the fold the undistortion map turns singular and bilinear rays go wrong (0.17 px
        // at Dataset 3's left fold): such pixels, detected by their centre, take exact rays too.
        const recon::Undistorted u = cam.undistort(Eigen::Vector2d(c, r));
        Eigen::Vector2d bilinear = Eigen::Vector2d::Zero();
        for (std::size_t k : {k00, k00 + 1, k00 + kc, k00 + kc + 1})
          bilinear += 0.25 * Eigen::Vector2d(t.corner[2 * k], t.corner[2 * k + 1]);
        const double err = (cam.project(bilinear.homogeneous()) - Eigen::Vector2d(c, r)).norm();
        if (!u.ok() || !(err <= kMaxInterpolationErrorPx)) all_valid = false;
        sum = u.normalized;
        valid = u.ok() ? 1 : 0;
      }
      if (!all_valid) {
        sum.setZero();
        valid = 0;
        // A pixel the fold crosses (or beyond it, or next to it): exact rays per sub-sample, NaN
        // where none exists.
        t.fold_pixels.push_back(static_cast<int>(p));
        t.exact[p] = 1;
        for (const auto& o : fold_offsets) {
          const recon::Undistorted u = cam.undistort(Eigen::Vector2d(c, r) + o);
          t.fold_rays.push_back(u.ok() ? static_cast<float>(u.normalized.x()) : kNaN);
          t.fold_rays.push_back(u.ok() ? static_cast<float>(u.normalized.y()) : kNaN);
          if (u.ok()) sum += u.normalized, ++valid;
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
  if (scene_.supersample < 1 || scene_.supersample > 64)
    throw std::invalid_argument("sim: supersample must be in 1..64");
  if (rig.left.width() != kSensorSize || rig.left.height() != kSensorSize ||
      rig.right.width() != kSensorSize || rig.right.height() != kSensorSize)
    throw std::invalid_argument("sim: the rig's cameras must be 250 x 250 (NanEye 2D)");
  rays_[0] = build_rays(rig_.left);
  rays_[1] = build_rays(rig_.right);
  for (const auto& o : sample_offsets(scene_.supersample)) {
    const double fx = o.x() + 0.5, fy = o.y() + 0.5;
    edge_weights_.push_back({(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy});
  }
}

void Renderer::irradiance_into(Eye eye, const Pose& board, bool present, Scratch& scratch, float* out) const {
  constexpr int kc = kSensorSize + 1;
  const RayTable& rt = rays_[static_cast<int>(eye)];
  const View view = make_view(rig_, eye, board, scene_);
  const Pattern pattern(scene_);
  const Eigen::Matrix3d& H = view.ray_to_board;
  // Plain numbers for the inner loops (unoptimised builds would call an accessor per coefficient).
  const double h00 = H(0, 0), h01 = H(0, 1), h02 = H(0, 2), h10 = H(1, 0), h11 = H(1, 1), h12 = H(1, 2),
               h20 = H(2, 0), h21 = H(2, 1), h22 = H(2, 2);
  // Board value of a ray: reflectance, or < 0 for the background (missed, behind, or off the board).
  auto value = [&](double x, double y) {
    const double w = h20 * x + h21 * y + h22;
    if (!present || !(w > 0.0)) return -1.0;
    const double iw = 1.0 / w;
    return pattern((h00 * x + h01 * y + h02) * iw, (h10 * x + h11 * y + h12) * iw);
  };
  auto cell = [&](double x, double y) {
    const double w = h20 * x + h21 * y + h22;
    if (!present || !(w > 0.0)) return Pattern::kBackground;
    const double iw = 1.0 / w;
    return pattern.cell((h00 * x + h01 * y + h02) * iw, (h10 * x + h11 * y + h12) * iw);
  };
  // Per frame: the region of every pixel corner. Uniform pixels need nothing else.
  std::vector<int>& cells = scratch.cells;
  cells.resize(static_cast<std::size_t>(kc) * kc);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const double x = rt.corner[2 * k], y = rt.corner[2 * k + 1];
    cells[k] = std::isnan(x) ? std::numeric_limits<int>::min() : cell(x, y);
  }
  // Each pixel: the fraction of its area on the board (weighted by reflectance) and on the background.
  std::vector<float>& board_part = scratch.board_part;
  std::vector<float>& background_part = scratch.background_part;
  board_part.assign(static_cast<std::size_t>(kSensorSize) * kSensorSize, 0.0f);
  background_part.assign(static_cast<std::size_t>(kSensorSize) * kSensorSize, 0.0f);
  const double inv_edge = 1.0 / static_cast<double>(edge_weights_.size());
  for (int r = 0; r < kSensorSize; ++r) {
    for (int c = 0; c < kSensorSize; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * kSensorSize + c;
      const std::size_t k00 = static_cast<std::size_t>(r) * kc + c, k01 = k00 + 1, k10 = k00 + kc,
                        k11 = k10 + 1;
      const int id = cells[k00];
      if (rt.exact[p]) continue;  // the fold pass below
      if (id == std::numeric_limits<int>::min() || cells[k01] == std::numeric_limits<int>::min() ||
          cells[k10] == std::numeric_limits<int>::min() || cells[k11] == std::numeric_limits<int>::min())
        continue;  // touches the fold: the fold pass below
      if (id == cells[k01] && id == cells[k10] && id == cells[k11]) {
        // Uniform: its centre tells the reflectance.
        const double a = value(rt.corner[2 * k00] * 0.25 + rt.corner[2 * k01] * 0.25 +
                                   rt.corner[2 * k10] * 0.25 + rt.corner[2 * k11] * 0.25,
                               rt.corner[2 * k00 + 1] * 0.25 + rt.corner[2 * k01 + 1] * 0.25 +
                                   rt.corner[2 * k10 + 1] * 0.25 + rt.corner[2 * k11 + 1] * 0.25);
        (a < 0 ? background_part[p] : board_part[p]) = static_cast<float>(a < 0 ? 1.0 : a);
        continue;
      }
      // An edge crosses the pixel: integrate it with the lattice of edge samples.
      const double* c00 = &rt.corner[2 * k00];
      const double* c01 = &rt.corner[2 * k01];
      const double* c10 = &rt.corner[2 * k10];
      const double* c11 = &rt.corner[2 * k11];
      double board_sum = 0.0;
      int background = 0;
      for (const Bilinear& w : edge_weights_) {
        const double x = w.w00 * c00[0] + w.w01 * c01[0] + w.w10 * c10[0] + w.w11 * c11[0];
        const double y = w.w00 * c00[1] + w.w01 * c01[1] + w.w10 * c10[1] + w.w11 * c11[1];
        const double a = value(x, y);
        if (a < 0.0)
          ++background;
        else
          board_sum += a;
      }
      board_part[p] = static_cast<float>(board_sum * inv_edge);
      background_part[p] = static_cast<float>(background * inv_edge);
    }
  }
  // Pixels the fold crosses: exact rays per sub-sample, none beyond the fold (no light there).
  const int nf = kFoldSamplesPerSide * kFoldSamplesPerSide;
  for (std::size_t i = 0; i < rt.fold_pixels.size(); ++i) {
    const float* s = &rt.fold_rays[i * nf * 2];
    double board_sum = 0.0;
    int background = 0;
    for (int k = 0; k < nf; ++k) {
      if (std::isnan(s[2 * k])) continue;
      const double a = value(s[2 * k], s[2 * k + 1]);
      if (a < 0.0)
        ++background;
      else
        board_sum += a;
    }
    board_part[rt.fold_pixels[i]] = static_cast<float>(board_sum / nf);
    background_part[rt.fold_pixels[i]] = static_cast<float>(static_cast<double>(background) / nf);
  }
  // Shading is smooth: evaluated once per pixel, on its centre ray.
  const double ref2 = scene_.light_reference_mm * scene_.light_reference_mm;
  for (std::size_t p = 0; p < board_part.size(); ++p) {
    double light = 1.0;
    if (scene_.lighting && board_part[p] > 0.0f) {
      const double cx = rt.centre[2 * p], cy = rt.centre[2 * p + 1];
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
    double v = board_part[p] * light + background_part[p] * scene_.background;
    if (sensor_.settings().vignetting) v *= rt.cos4[p];
    out[p] = static_cast<float>(v);
  }
}

cv::Mat Renderer::irradiance(Eye eye, const Pose& board) const {
  cv::Mat m(kSensorSize, kSensorSize, CV_32FC1);
  Scratch scratch;
  irradiance_into(eye, board, scene_.board_present, scratch, m.ptr<float>());
  return m;
}

RenderedPair Renderer::render(const Pose& board, Rng& rng) const {
  RenderedPair out;
  out.left.create(kSensorSize, kSensorSize, CV_16UC1);
  out.right.create(kSensorSize, kSensorSize, CV_16UC1);
  Scratch scratch;
  render_into(board, rng, out.left.ptr<std::uint16_t>(), out.right.ptr<std::uint16_t>(), scratch);
  out.truth = compute_truth(rig_, scene_.board, board, scene_.board_present);
  return out;
}

void Renderer::render_into(const Pose& board, Rng& rng, std::uint16_t* left, std::uint16_t* right,
                           Scratch& scratch) const {
  scratch.light.create(kSensorSize, kSensorSize, CV_32FC1);
  irradiance_into(Eye::left, board, scene_.board_present, scratch, scratch.light.ptr<float>());
  sensor_.expose(static_cast<int>(Eye::left), scratch.light, rng, scratch.sensor, left);
  irradiance_into(Eye::right, board, scene_.board_present, scratch, scratch.light.ptr<float>());
  sensor_.expose(static_cast<int>(Eye::right), scratch.light, rng, scratch.sensor, right);
}

void Renderer::render_background_into(Rng& rng, std::uint16_t* left, std::uint16_t* right,
                                      Scratch& scratch) const {
  scratch.light.create(kSensorSize, kSensorSize, CV_32FC1);
  irradiance_into(Eye::left, Pose{}, false, scratch, scratch.light.ptr<float>());
  sensor_.expose(static_cast<int>(Eye::left), scratch.light, rng, scratch.sensor, left);
  irradiance_into(Eye::right, Pose{}, false, scratch, scratch.light.ptr<float>());
  sensor_.expose(static_cast<int>(Eye::right), scratch.light, rng, scratch.sensor, right);
}

RenderedPair render_pair(const SceneSettings& scene, const SensorSettings& sensor,
                         const recon::StereoRig& rig, const Pose& board, Rng& rng) {
  return Renderer(rig, scene, sensor).render(board, rng);
}

recon::RawImageView raw_view(const cv::Mat& image, bool bayer) {
  recon::RawImageView v;
  v.data = image.ptr<std::uint16_t>();
  v.width = image.cols;
  v.height = image.rows;
  v.stride = static_cast<int>(image.step1());
  v.layout = bayer ? recon::PixelLayout::bayer_grbg : recon::PixelLayout::mono;
  return v;
}

}  // namespace naneye::sim
