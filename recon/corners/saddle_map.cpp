// Saddle candidates for the full-search coarse grid (corners/coarse_grid.hpp): the Hessian determinant
// of a lightly smoothed luminance, 5x5 non-maximum suppression, a quadratic sub-pixel peak and a
// ring test. Hand-written rather than cv::GaussianBlur / cv::Sobel because OpenCV's filter engine
// allocates on every call and the daemon must not allocate per frame.
#include <algorithm>
#include <array>
#include <cmath>

#include "naneye/recon/corners/coarse_grid.hpp"

namespace naneye::recon {

namespace {
// cos(2 pi k / 16), k = 0..15: the 16 ring directions (sin is the cosine a quarter turn later).
constexpr std::array<float, 16> kRingCos = {
    1.0f,  0.92387953f,  0.70710678f,  0.38268343f,  0.0f, -0.38268343f, -0.70710678f, -0.92387953f,
    -1.0f, -0.92387953f, -0.70710678f, -0.38268343f, 0.0f, 0.38268343f,  0.70710678f,  0.92387953f};
constexpr float ring_sin(int k) {
  return kRingCos[static_cast<std::size_t>((k + 12) % 16)];
}

float bilinear(const float* img, int width, float x, float y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);  // callers keep x, y >= 0
  const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
  const float* p = img + y0 * width + x0;
  return (p[0] * (1 - fx) + p[1] * fx) * (1 - fy) + (p[width] * (1 - fx) + p[width + 1] * fx) * fy;
}
}  // namespace

CoarseGridFinder::CoarseGridFinder(const CameraModel& cam, const CoarseGridSettings& settings)
    : s_(settings), cam_(cam), width_(cam.width()), height_(cam.height()) {
  const auto n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  tmp_.assign(n, 0.0f);
  smooth_.assign(n, 0.0f);
  resp_.assign(n, 0.0f);
  cand_.resize(kCandidateCapacity);
  order_.resize(kCandidateCapacity);
  cell_of_.resize(kCandidateCapacity);
  grid_.resize(static_cast<std::size_t>(kMaxSide) * kMaxSide);
  lut_w_ = (width_ - 1 + kLutStep - 1) / kLutStep + 1;
  lut_h_ = (height_ - 1 + kLutStep - 1) / kLutStep + 1;
  lut_.resize(static_cast<std::size_t>(lut_w_) * lut_h_);
  lut_ok_.assign(lut_.size(), 0);
  std::vector<unsigned char> node_ok(lut_.size());
  for (int j = 0; j < lut_h_; ++j) {
    for (int i = 0; i < lut_w_; ++i) {
      const auto k = static_cast<std::size_t>(j * lut_w_ + i);
      const Undistorted u = cam.undistort(Eigen::Vector2d(i * kLutStep, j * kLutStep));
      node_ok[k] = u.ok();
      lut_[k] = Eigen::Vector2f::Zero();
      if (u.ok()) lut_[k] = (u.normalized * cam.fx()).cast<float>();
    }
  }
  // A cell is interpolated when its four nodes are in the domain and bilinear interpolation meets
  // the exact inverse at the cell centre (where its error peaks) within kLutTolerancePx; the cells
  // next to the fold, where the inverse's derivative grows without bound, use the exact inverse.
  for (int j = 0; j + 1 < lut_h_; ++j) {
    for (int i = 0; i + 1 < lut_w_; ++i) {
      const auto k = static_cast<std::size_t>(j * lut_w_ + i), w = static_cast<std::size_t>(lut_w_);
      if (!node_ok[k] || !node_ok[k + 1] || !node_ok[k + w] || !node_ok[k + w + 1]) continue;
      const Undistorted c = cam.undistort(Eigen::Vector2d((i + 0.5) * kLutStep, (j + 0.5) * kLutStep));
      if (!c.ok()) continue;
      const Eigen::Vector2f mid = 0.25f * (lut_[k] + lut_[k + 1] + lut_[k + w] + lut_[k + w + 1]);
      lut_ok_[k] = (mid - (c.normalized * cam.fx()).cast<float>()).norm() <= kLutTolerancePx;
    }
  }
}

bool CoarseGridFinder::undistort_px(const Eigen::Vector2f& px, Eigen::Vector2f& und) const {
  const float x = px.x() / kLutStep, y = px.y() / kLutStep;
  if (!(x >= 0 && y >= 0 && x <= static_cast<float>(lut_w_ - 1) && y <= static_cast<float>(lut_h_ - 1))) {
    return false;
  }
  const int i = std::min(static_cast<int>(x), lut_w_ - 2), j = std::min(static_cast<int>(y), lut_h_ - 2);
  const auto k = static_cast<std::size_t>(j * lut_w_ + i), w = static_cast<std::size_t>(lut_w_);
  if (!lut_ok_[k]) {
    const Undistorted u = cam_.undistort(px.cast<double>());
    if (!u.ok()) return false;
    und = (u.normalized * cam_.fx()).cast<float>();
    return true;
  }
  const float fx = x - static_cast<float>(i), fy = y - static_cast<float>(j);
  und = (lut_[k] * (1 - fx) + lut_[k + 1] * fx) * (1 - fy) +
        (lut_[k + w] * (1 - fx) + lut_[k + w + 1] * fx) * fy;
  return true;
}

void CoarseGridFinder::saddle_map(const LumaView& img) {
  // Binomial [1 4 6 4 1] / 16 (sigma = 1 px) in both directions, reads clamped to the usable area,
  // then -det(H) from central differences: a saddle has det < 0 at its centre, an edge det ~ 0.
  // Rows as Eigen arrays: Eigen vectorises them explicitly (GCC does not at -O2) and maps of
  // existing buffers allocate nothing.
  using Row = Eigen::Map<Eigen::ArrayXf>;
  using CRow = Eigen::Map<const Eigen::ArrayXf>;
  const int w = width_, rb = img.row_begin, re = img.row_end, ce = img.col_end;
  const float k0 = 6.0f / 16, k1 = 4.0f / 16, k2 = 1.0f / 16;
  for (int r = rb; r < re; ++r) {
    const float* in = img.data + r * w;
    float* o = tmp_.data() + r * w;
    const int n = ce - 4;
    Row(o + 2, n) = k0 * CRow(in + 2, n) + k1 * (CRow(in + 1, n) + CRow(in + 3, n)) +
                    k2 * (CRow(in, n) + CRow(in + 4, n));
    for (int c : {0, 1, ce - 2, ce - 1}) {
      auto at = [&](int cc) { return in[std::clamp(cc, 0, ce - 1)]; };
      o[c] = k0 * at(c) + k1 * (at(c - 1) + at(c + 1)) + k2 * (at(c - 2) + at(c + 2));
    }
  }
  for (int r = rb; r < re; ++r) {
    auto row = [&](int rr) { return CRow(tmp_.data() + std::clamp(rr, rb, re - 1) * w, ce); };
    Row(smooth_.data() + r * w, ce) =
        k0 * row(r) + k1 * (row(r - 1) + row(r + 1)) + k2 * (row(r - 2) + row(r + 2));
  }
  // collect_candidates reads the response up to the usable area's border: the border rows and
  // columns, where there is no central difference, are zero.
  std::fill(resp_.begin() + rb * w, resp_.begin() + (rb + 1) * w, 0.0f);
  std::fill(resp_.begin() + (re - 1) * w, resp_.begin() + re * w, 0.0f);
  float peak = 0;
  for (int r = rb + 1; r + 1 < re; ++r) {
    const int n = ce - 2;
    auto at = [&](int dr, int dc) { return CRow(smooth_.data() + (r + dr) * w + 1 + dc, n); };
    Row resp(resp_.data() + r * w + 1, n);
    resp = (0.25f * (at(1, 1) - at(1, -1) - at(-1, 1) + at(-1, -1))).square() -
           (at(0, -1) - 2 * at(0, 0) + at(0, 1)) * (at(-1, 0) - 2 * at(0, 0) + at(1, 0));
    resp_[static_cast<std::size_t>(r * w)] = 0;
    resp_[static_cast<std::size_t>(r * w + ce - 1)] = 0;
    peak = std::max(peak, resp.maxCoeff());
  }
  peak_ = peak;
}

bool CoarseGridFinder::ring_test(const LumaView& img, SaddleCandidate& c) const {
  // A checkerboard saddle is point-symmetric about its centre, so on a circle around it the odd
  // angular harmonics vanish and the second (four alternating quadrants) dominates; an edge or the
  // L-shaped corner of a border square is not, and has a first harmonic as large as the second.
  const float rad = s_.ring_radius;
  if (c.px.x() - rad < 0 || c.px.x() + rad + 1 >= static_cast<float>(img.col_end) ||
      c.px.y() - rad < static_cast<float>(img.row_begin) ||
      c.px.y() + rad + 1 >= static_cast<float>(img.row_end)) {
    return false;
  }
  float a1 = 0, b1 = 0, a2 = 0, b2 = 0;
  for (int k = 0; k < 16; ++k) {
    const float cs = kRingCos[static_cast<std::size_t>(k)], sn = ring_sin(k);
    const float f = bilinear(smooth_.data(), width_, c.px.x() + rad * cs, c.px.y() + rad * sn);
    a1 += f * cs;
    b1 += f * sn;
    a2 += f * (cs * cs - sn * sn);
    b2 += f * (2 * cs * sn);
  }
  const float h1 = std::hypot(a1, b1), h2 = std::hypot(a2, b2);
  c.phase = {a2, b2};
  const float level = bilinear(smooth_.data(), width_, c.px.x(), c.px.y());
  const float min_amp = noise_ ? s_.min_ring_snr * std::sqrt(static_cast<float>(noise_->variance(level)))
                               : s_.min_ring_amplitude_dn;
  return h2 >= s_.min_harmonic_ratio * h1 && h2 * (2.0f / 16) >= min_amp;
}

void CoarseGridFinder::collect_candidates(const LumaView& img) {
  // A cluttered photograph can hold more saddles than the buffer: rather than keep the first rows'
  // only (scan order), raise the floor by 2 (sqrt 2 in contrast) until the strongest ones fit.
  for (float boost = 1.0f; boost < 1e6f; boost *= 2.0f) {
    if (collect_candidates(img, boost)) return;
  }
}

bool CoarseGridFinder::collect_candidates(const LumaView& img, float boost) {
  const int w = width_;
  count_ = 0;
  constexpr float kPi = 3.14159265f;
  const float floor = s_.min_saddle_contrast_dn / (2.0f * kPi);
  const float relative = s_.min_relative_response * peak_;
  // With a noise model the floor is (snr sigma(level) / 2 pi)^2, sigma at the smoothed level; the
  // smallest it can be (the read noise alone) screens most pixels before the per-pixel bound.
  const float snr2 = s_.min_saddle_snr * s_.min_saddle_snr / (4.0f * kPi * kPi);
  const float threshold = boost * (noise_ ? std::max(relative, snr2 * static_cast<float>(noise_->b))
                                          : std::max(relative, floor * floor));
  for (int r = img.row_begin + 2; r + 2 < img.row_end; ++r) {
    for (int c = 2; c + 2 < img.col_end; ++c) {
      const float* p = resp_.data() + r * w + c;
      const float v = *p;
      if (v < threshold) continue;
      if (noise_ &&
          v < boost * snr2 *
                  static_cast<float>(noise_->variance(smooth_[static_cast<std::size_t>(r * w + c)]))) {
        continue;
      }
      bool is_max = true;
      // Ties go to the first pixel in scan order, so a flat top gives one candidate.
      for (int dr = -2; dr <= 2 && is_max; ++dr) {
        for (int dc = -2; dc <= 2; ++dc) {
          const float q = p[dr * w + dc];
          const bool before = dr < 0 || (dr == 0 && dc < 0);
          if (q > v || (before && q == v)) {
            is_max = false;
            break;
          }
        }
      }
      if (!is_max) continue;
      // Quadratic peak per axis; the denominators are negative at a strict maximum.
      const float l = p[-1], rr = p[1], u = p[-w], d = p[w];
      const float dx = (l - 2 * v + rr) < 0 ? 0.5f * (l - rr) / (l - 2 * v + rr) : 0.0f;
      const float dy = (u - 2 * v + d) < 0 ? 0.5f * (u - d) / (u - 2 * v + d) : 0.0f;
      SaddleCandidate& cand = cand_[static_cast<std::size_t>(count_)];
      cand.px = {static_cast<float>(c) + std::clamp(dx, -0.5f, 0.5f),
                 static_cast<float>(r) + std::clamp(dy, -0.5f, 0.5f)};
      cand.response = v;
      cand.usable = false;
      if (!ring_test(img, cand)) continue;
      if (++count_ == kCandidateCapacity) return false;
    }
  }
  return true;
}

}  // namespace naneye::recon
