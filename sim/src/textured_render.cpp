// Rendering of the textured scenes of textured.hpp: exact rays per sub-sample (CameraModel::undistort),
// analytic intersection, solid texture, a point light at the camera with cos(incidence) / d^2, the
// lens's cos^4, then the sensor of sensor_model.hpp (the board renderer's: blur, Bayer gains,
// fixed-pattern noise, the reset line, shot and read noise, defects, 10 bits).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "naneye/driver/frame.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::sim {
namespace {
using driver::kSensorSize;

struct Wave3 {
  Eigen::Vector3d k;  // rad/mm
  double phase;
};

std::vector<Wave3> texture_waves(const TextureSettings& t) {
  Rng g(t.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<Wave3> w(static_cast<std::size_t>(std::max(1, t.components)));
  for (auto& c : w) {
    Eigen::Vector3d dir(n01(g), n01(g), n01(g));
    dir.normalize();
    const double f =
        1.0 / t.wavelength_max_mm + u01(g) * (1.0 / t.wavelength_min_mm - 1.0 / t.wavelength_max_mm);
    c.k = 2 * std::numbers::pi * f * dir;
    c.phase = 2 * std::numbers::pi * u01(g);
  }
  return w;
}

double reflectance(const std::vector<Wave3>& w, const TextureSettings& t, const Eigen::Vector3d& X) {
  double s = 0;
  for (const auto& c : w) s += std::cos(c.k.dot(X) + c.phase);
  // Each cos has variance 1/2: the sum / sqrt(K / 2) has unit variance.
  const double v = t.mean + t.contrast * s / std::sqrt(0.5 * static_cast<double>(w.size()));
  return std::clamp(v, 0.02, 1.0);
}

// The texture as render_frames evaluates it: the same waves in single precision, the cosine by a
// polynomial, in blocks of 8 the compiler turns into vector code. ~6x faster than K calls of
// std::cos in double; its reflectance differs from reflectance() by < 1e-5 (float phases of up to
// ~500 rad), a hundredth of a 10-bit step, so the live frames are the scene's, a few times faster.
struct FastWaves {
  static constexpr int kBlock = 8;
  std::vector<float> kx, ky, kz, phase, weight;  // padded to a multiple of kBlock with weight 0
  float norm = 1;
};

FastWaves fast_waves(const std::vector<Wave3>& w) {
  FastWaves f;
  const std::size_t n = (w.size() + FastWaves::kBlock - 1) / FastWaves::kBlock * FastWaves::kBlock;
  f.kx.assign(n, 0.f), f.ky.assign(n, 0.f), f.kz.assign(n, 0.f), f.phase.assign(n, 0.f),
      f.weight.assign(n, 0.f);
  for (std::size_t i = 0; i < w.size(); ++i) {
    f.kx[i] = static_cast<float>(w[i].k.x()), f.ky[i] = static_cast<float>(w[i].k.y());
    f.kz[i] = static_cast<float>(w[i].k.z()), f.phase[i] = static_cast<float>(w[i].phase), f.weight[i] = 1.f;
  }
  f.norm = static_cast<float>(1.0 / std::sqrt(0.5 * static_cast<double>(w.size())));
  return f;
}

// cos(a) for any float a: reduced to [-pi, pi] (rounding by the 1.5 * 2^23 trick, which needs no
// SSE4.1 instruction), folded to [0, pi / 2], then Taylor to the 12th power (error < 5e-7).
inline float fast_cos(float a) {
  constexpr float kInv2Pi = 0.15915494309189535f, k2PiHi = 6.28125f, k2PiLo = 0.0019353071795864769f;
  constexpr float kMagic = 12582912.0f;  // 1.5 * 2^23
  const float n = (a * kInv2Pi + kMagic) - kMagic;
  const float r = (a - n * k2PiHi) - n * k2PiLo;  // [-pi, pi]
  const float y = r < 0 ? -r : r;
  const bool far = y > 1.5707963267948966f;
  const float c = far ? 3.14159265358979f - y : y;
  const float c2 = c * c;
  const float p =
      1.f +
      c2 * (-0.5f + c2 * (1.f / 24 + c2 * (-1.f / 720 + c2 * (1.f / 40320 + c2 * (-1.f / 3628800 +
                                                                                  c2 * (1.f / 479001600))))));
  return far ? -p : p;
}

double fast_reflectance(const FastWaves& w, const TextureSettings& t, const Eigen::Vector3d& X) {
  const float x = static_cast<float>(X.x()), y = static_cast<float>(X.y()), z = static_cast<float>(X.z());
  float sum = 0;
  for (std::size_t b = 0; b < w.kx.size(); b += FastWaves::kBlock) {
    float part[FastWaves::kBlock];
    for (int j = 0; j < FastWaves::kBlock; ++j) {
      const std::size_t i = b + static_cast<std::size_t>(j);
      part[j] = w.weight[i] * fast_cos(w.kx[i] * x + w.ky[i] * y + w.kz[i] * z + w.phase[i]);
    }
    for (float v : part) sum += v;
  }
  return std::clamp(t.mean + t.contrast * static_cast<double>(sum * w.norm), 0.02, 1.0);
}

// Active pixels a point may be seen at: column 249 and the last row are padding/reference.
bool in_active(const Eigen::Vector2d& px) {
  return px.x() >= -0.5 && px.x() <= kSensorSize - 1.5 && px.y() >= -0.5 && px.y() <= kSensorSize - 1.5;
}
}  // namespace

TexturedRenderer::TexturedRenderer(const recon::StereoRig& rig, const SensorSettings& sensor, int supersample)
    : rig_(rig), sensor_(sensor), n_(std::max(1, supersample)) {
  rays_[0] = build(rig_.left);
  rays_[1] = build(rig_.right);
}

TexturedRenderer::Rays TexturedRenderer::build(const recon::CameraModel& cam) const {
  Rays r;
  const std::size_t np = static_cast<std::size_t>(kSensorSize) * kSensorSize;
  r.sub.assign(np * n_ * n_ * 2, NAN);
  r.centre.assign(np * 2, NAN);
  r.cos4.assign(np, 0.f);
  for (int row = 0; row < kSensorSize; ++row)
    for (int col = 0; col < kSensorSize; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * kSensorSize + col;
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) {
          const Eigen::Vector2d px(col - 0.5 + (j + 0.5) / n_, row - 0.5 + (i + 0.5) / n_);
          const recon::Undistorted u = cam.undistort(px);
          if (!u.ok()) continue;
          const std::size_t k = (p * n_ * n_ + static_cast<std::size_t>(i * n_ + j)) * 2;
          r.sub[k] = static_cast<float>(u.normalized.x());
          r.sub[k + 1] = static_cast<float>(u.normalized.y());
        }
      const recon::Undistorted u = cam.undistort(Eigen::Vector2d(col, row));
      if (!u.ok()) continue;
      r.centre[2 * p] = static_cast<float>(u.normalized.x());
      r.centre[2 * p + 1] = static_cast<float>(u.normalized.y());
      const double c2 = 1.0 / (1.0 + u.normalized.squaredNorm());
      r.cos4[p] = static_cast<float>(c2 * c2);
    }
  return r;
}

void TexturedRenderer::irradiance(int eye, const TexturedSceneSettings& scene, cv::Mat& out,
                                  bool fast) const {
  out.create(kSensorSize, kSensorSize, CV_32FC1);
  const auto waves = texture_waves(scene.texture);
  const FastWaves fw = fast_waves(waves);
  const Rays& rt = rays_[eye];
  const Eigen::Vector3d o = eye == 0 ? Eigen::Vector3d::Zero() : rig_.right_center();
  const Eigen::Matrix3d Rt = eye == 0 ? Eigen::Matrix3d::Identity() : Eigen::Matrix3d(rig_.R.transpose());
  const double ref2 = scene.light_reference_mm * scene.light_reference_mm;
  const int nn = n_ * n_;
  for (int row = 0; row < kSensorSize; ++row) {
    float* dst = out.ptr<float>(row);
    for (int col = 0; col < kSensorSize; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * kSensorSize + col;
      double sum = 0;
      for (int k = 0; k < nn; ++k) {
        const float x = rt.sub[(p * nn + k) * 2], y = rt.sub[(p * nn + k) * 2 + 1];
        if (std::isnan(x)) continue;  // beyond the fold: no ray, no light
        const Eigen::Vector3d d = (Rt * Eigen::Vector3d(x, y, 1.0)).normalized();
        const auto t = scene.surface.intersect(o, d);
        if (!t) continue;
        const Eigen::Vector3d X = o + *t * d;
        const Eigen::Vector3d l = scene.light_mm - X;
        const double d2 = l.squaredNorm();
        const double cos_i = std::abs(scene.surface.normal(X).dot(l)) / std::sqrt(d2);
        const Eigen::Vector3d local = scene.surface.to_local(X);
        const double rho =
            fast ? fast_reflectance(fw, scene.texture, local) : reflectance(waves, scene.texture, local);
        sum += rho * cos_i * ref2 / d2;
      }
      dst[col] = static_cast<float>(sum / nn * (sensor_.settings().vignetting ? rt.cos4[p] : 1.0f));
    }
  }
}

void TexturedRenderer::expose(int eye, const cv::Mat& light, Rng& rng, cv::Mat& out) const {
  out.create(kSensorSize, kSensorSize, CV_16UC1);
  SensorModel::Scratch scratch;
  sensor_.expose(eye, light, rng, scratch, out.ptr<std::uint16_t>());
}

bool TexturedRenderer::right_sees(const Surface& s, const Eigen::Vector3d& X) const {
  const Eigen::Vector3d Xr = rig_.R * X + rig_.T;
  if (!(Xr.z() > 0)) return false;
  const Eigen::Vector2d px = rig_.right.project(Xr);
  if (!in_active(px)) return false;
  // A projection beyond the fold is a folded-back number no ray reaches: the round trip tells.
  const recon::Undistorted u = rig_.right.undistort(px);
  if (!u.ok() || (u.normalized - Xr.head<2>() / Xr.z()).norm() > 1e-9) return false;
  const Eigen::Vector3d c = rig_.right_center();
  const Eigen::Vector3d d = X - c;
  const double len = d.norm();
  const auto t = s.intersect(c, d / len);
  return t && *t >= len * (1 - 1e-9);
}

std::optional<double> TexturedRenderer::truth_depth_at(const Surface& s,
                                                       const Eigen::Vector2d& left_px) const {
  if (!in_active(left_px)) return std::nullopt;
  const recon::Undistorted u = rig_.left.undistort(left_px);
  if (!u.ok()) return std::nullopt;
  const Eigen::Vector3d d = Eigen::Vector3d(u.normalized.x(), u.normalized.y(), 1.0).normalized();
  const auto t = s.intersect(Eigen::Vector3d::Zero(), d);
  if (!t) return std::nullopt;
  const Eigen::Vector3d X = *t * d;
  if (!right_sees(s, X)) return std::nullopt;
  return X.z();
}

cv::Mat TexturedRenderer::truth_depth(const Surface& s) const {
  cv::Mat depth(kSensorSize, kSensorSize, CV_64FC1, cv::Scalar(NAN));
  for (int r = 0; r < kSensorSize; ++r)
    for (int c = 0; c < kSensorSize; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * kSensorSize + c;
      if (std::isnan(rays_[0].centre[2 * p])) continue;
      if (auto z = truth_depth_at(s, Eigen::Vector2d(c, r))) depth.at<double>(r, c) = *z;
    }
  return depth;
}

void TexturedRenderer::render_frames(const TexturedSceneSettings& scene, Rng& rng, cv::Mat& left,
                                     cv::Mat& right) const {
  cv::Mat light;
  irradiance(0, scene, light, true);
  expose(0, light, rng, left);
  irradiance(1, scene, light, true);
  expose(1, light, rng, right);
}

TexturedPair TexturedRenderer::render(const TexturedSceneSettings& scene, Rng& rng) const {
  TexturedPair out;
  cv::Mat light;
  irradiance(0, scene, light);
  expose(0, light, rng, out.left);
  irradiance(1, scene, light);
  expose(1, light, rng, out.right);
  out.depth = truth_depth(scene.surface);
  return out;
}

TexturedPair numbered_render(const TexturedRenderer& renderer, const std::string& preset, int k) {
  const std::optional<TexturedSceneSettings> found = textured_preset(preset);
  if (!found) throw std::invalid_argument("numbered_render: unknown textured preset '" + preset + "'");
  TexturedSceneSettings scene = *found;
  scene.texture.seed += static_cast<std::uint64_t>(100 * k);
  Rng rng(1000 + static_cast<std::uint64_t>(k));
  return renderer.render(scene, rng);
}

}  // namespace naneye::sim
