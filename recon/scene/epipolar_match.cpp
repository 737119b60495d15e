// Epipolar curve sampling and the coarse ZNCC search along it (epipolar_match.hpp).
#include "naneye/recon/scene/epipolar_match.hpp"

#include <algorithm>
#include <cmath>

#include "../corners/simd.hpp"
#include "round.hpp"

namespace naneye::recon::scene {
namespace {
Eigen::Vector2d curve_point(const CameraModel& cam, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            double w, bool& inside) {
  const Eigen::Vector3d X = a + b * w;  // proportional to the point in the other frame
  inside = X.z() > 0;
  const Eigen::Vector2d xn = X.head<2>() / X.z();
  if (const auto fold = cam.fold_radius_undistorted(); fold && xn.norm() >= *fold) inside = false;
  return cam.to_pixel(cam.distort(xn));
}
// The template's padded rows (`stride` floats each) times the image's rows from `row0`, summed in
// four lanes, rows top to bottom, each row's vectors left to right. The default window (7 x 7,
// stride 8) gets its own instance with the loops' bounds known (unrolled: match_along_curve 13.5 M ->
// 8.9 M instructions, callgrind on the plane); both give the same bits.
template <int Side = 0, int Stride = 0>
simd::V4 padded_dot(const float* tp, const float* row0, int width, int side = Side, int stride = Stride) {
  if constexpr (Side > 0) {
    side = Side;
    stride = Stride;
  }
  simd::V4 acc{};
  for (int dr = 0; dr < side; ++dr) {
    const float* row = row0 + dr * width;
    for (int j = 0; j < stride; j += 4)
      acc += simd::load<simd::V4>(tp + dr * stride + j) * simd::load<simd::V4>(row + j);
  }
  return acc;
}
}  // namespace

void sample_epipolar_curve(const CameraModel& other, const Eigen::Matrix3d& R, const Eigen::Vector3d& T,
                           const Eigen::Vector2d& xn, double w_min, double w_max, double step_px,
                           EpipolarCurve& out) {
  const Eigen::Vector3d a = R * Eigen::Vector3d(xn.x(), xn.y(), 1.0);
  bool in0 = false, in1 = false;
  const Eigen::Vector2d p0 = curve_point(other, a, T, w_min, in0), p1 = curve_point(other, a, T, w_max, in1);
  // The curve bends only slightly over tens of pixels: its chord sets the sample count.
  const double len = (p1 - p0).norm();
  out.n = std::clamp(static_cast<int>(std::ceil(len / step_px)) + 1, 2, EpipolarCurve::kMaxSamples);
  for (int i = 0; i < out.n; ++i) {
    const double w = w_min + (w_max - w_min) * i / (out.n - 1);
    bool inside = false;
    out.px[i] = curve_point(other, a, T, w, inside);
    out.w[i] = w;
    out.inside[i] = inside;
  }
}

void window_inverse_norms(const GrayView& img, int radius, const std::uint8_t* usable, float* out,
                          double* scratch) {
  const int w = img.width, h = img.height, side = 2 * radius + 1;
  std::fill(out, out + static_cast<std::size_t>(w) * h, 0.f);
  if (w < side || h < side) return;
  // Column sums over the window's rows, slid down one row at a time, then slid along each row: ~4
  // additions per pixel where an integral image costs eight reads and its own build (7.6 M of the
  // sparse path's 79 M instructions before). On integer samples (a mono sensor's DN) every sum is
  // exact in double, so the order does not matter; on a Bayer luminance the running sums drift by
  // ~1e-16 relative per row, far below the test against flat windows.
  double* c1 = scratch;
  double* c2 = scratch + w;
  for (int c = 0; c < w; ++c) c1[c] = c2[c] = 0;
  for (int r = 0; r < side; ++r)
    for (int c = 0; c < w; ++c) {
      const double v = img.at(c, r);
      c1[c] += v;
      c2[c] += v * v;
    }
  const double n = double(side) * side;
  for (int r = radius; r + radius < h; ++r) {
    if (r > radius)
      for (int c = 0; c < w; ++c) {
        const double a = img.at(c, r + radius), b = img.at(c, r - radius - 1);
        c1[c] += a - b;
        c2[c] += a * a - b * b;
      }
    double s1 = 0, s2 = 0;
    for (int c = 0; c < side; ++c) s1 += c1[c], s2 += c2[c];
    for (int c = radius; c + radius < w; ++c) {
      if (c > radius) {
        s1 += c1[c + radius] - c1[c - radius - 1];
        s2 += c2[c + radius] - c2[c - radius - 1];
      }
      if (!usable[r * w + c]) continue;
      const double var = s2 - s1 * s1 / n;
      // Cancellation leaves ~1e-16 s2 of noise: a flat window (var below 1e-9 s2) gets no score.
      if (var > 1e-9 * s2) out[r * w + c] = static_cast<float>(1.0 / std::sqrt(var));
    }
  }
}

CurveMatch match_along_curve(const GrayView& src, int u, int v, const GrayView& dst,
                             const std::uint8_t* dst_usable, const EpipolarCurve& curve, int radius,
                             const float* dst_inv_norm) {
  constexpr int kMaxWin = 15 * 15;
  const int side = 2 * radius + 1, n = side * side;
  CurveMatch m;
  if (n > kMaxWin) return m;
  std::array<float, kMaxWin> t{};
  double mean = 0;
  for (int dr = -radius, k = 0; dr <= radius; ++dr)
    for (int dc = -radius; dc <= radius; ++dc, ++k) mean += t[k] = src.at(u + dc, v + dr);
  mean /= n;
  double var = 0;
  for (int k = 0; k < n; ++k) {
    t[k] = static_cast<float>(t[k] - mean);
    var += double(t[k]) * t[k];
  }
  if (!(var > 0)) return m;
  const double tnorm = std::sqrt(var);
  // The template's rows padded with zeros to whole 4-float vectors (7 -> 8): a window's dot product
  // is then two vector products per row, summed in the lanes, where a plain loop could not be
  // vectorised (float addition does not reassociate). SSE2 is the x86-64 baseline: the same bits on
  // every machine.
  using simd::V4;
  constexpr int kMaxStride = 16;
  const int stride = (side + 3) / 4 * 4;
  std::array<float, kMaxStride * 15> tp{};
  for (int dr = 0; dr < side && stride <= kMaxStride; ++dr)
    for (int dc = 0; dc < side; ++dc) tp[dr * stride + dc] = t[dr * side + dc];
  std::array<double, EpipolarCurve::kMaxSamples> score{};
  int best = -1;
  for (int i = 0; i < curve.n; ++i) {
    score[i] = -2;
    if (!curve.inside[i]) continue;
    const int c = round_half_away(curve.px[i].x()), r = round_half_away(curve.px[i].y());
    if (c < 0 || r < 0 || c >= dst.width || r >= dst.height || !dst_usable[r * dst.width + c]) continue;
    // sum t' (I - mean_I) = sum t' I since sum t' = 0.
    double sdot = 0, si = 0, sii = 0;
    if (dst_inv_norm) {
      const float in = dst_inv_norm[r * dst.width + c];
      if (!(in > 0)) continue;
      if (stride <= kMaxStride && c - radius + stride <= dst.width) {
        // The padded columns are read (times zero): they must lie inside the row. Float sums of
        // 49 products of <= 2^20 each: ~1e-7 relative, far below a score's noise.
        const float* row0 = dst.data + (r - radius) * dst.width + c - radius;
        const V4 acc = radius == 3 ? padded_dot<7, 8>(tp.data(), row0, dst.width)
                                   : padded_dot(tp.data(), row0, dst.width, side, stride);
        sdot = (double(acc[0]) + acc[1]) + (double(acc[2]) + acc[3]);
      } else {
        // Float sums per row (7 products of <= 2^20 each: exact to ~1e-7 relative), double across rows.
        for (int dr = -radius, k = 0; dr <= radius; ++dr, k += side) {
          const float* row = dst.data + (r + dr) * dst.width + c - radius;
          float acc = 0;
          for (int dc = 0; dc < side; ++dc) acc += t[k + dc] * row[dc];
          sdot += acc;
        }
      }
      score[i] = sdot * in / tnorm;
    } else {
      for (int dr = -radius, k = 0; dr <= radius; ++dr) {
        const float* row = dst.data + (r + dr) * dst.width + c;
        for (int dc = -radius; dc <= radius; ++dc, ++k) {
          const double val = row[dc];
          sdot += t[k] * val;
          si += val;
          sii += val * val;
        }
      }
      const double vi = sii - si * si / n;
      if (!(vi > 0)) continue;
      score[i] = sdot / (tnorm * std::sqrt(vi));
    }
    if (best < 0 || score[i] > score[best]) best = i;
  }
  if (best < 0) return m;
  m.found = true;
  m.best = score[best];
  // The second best is the best of the other peaks: the samples beyond the best one's lobe (where
  // the score falls monotonically on either side). A fixed distance would take the lobe's own
  // shoulder for a second match where the texture is blurred: at 1.22 px blur the lobe is wider
  // than 2 samples and the tube's ambiguous features doubled.
  int lo = best, hi = best;
  while (lo > 0 && score[lo - 1] > -2 && score[lo - 1] <= score[lo]) --lo;
  while (hi + 1 < curve.n && score[hi + 1] > -2 && score[hi + 1] <= score[hi]) ++hi;
  for (int i = 0; i < curve.n; ++i)
    if (i < lo || i > hi) m.second = std::max(m.second, score[i]);
  double frac = 0;
  if (best > 0 && best + 1 < curve.n && score[best - 1] > -2 && score[best + 1] > -2) {
    const double a = score[best - 1], b = score[best], c = score[best + 1];
    const double den = a - 2 * b + c;
    if (den < 0) frac = std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
  }
  m.index = best + frac;
  const int j = frac >= 0 ? std::min(best + 1, curve.n - 1) : std::max(best - 1, 0);
  const double f = std::abs(frac);
  m.px = (1 - f) * curve.px[best] + f * curve.px[j];
  m.w = (1 - f) * curve.w[best] + f * curve.w[j];
  return m;
}

}  // namespace naneye::recon::scene
