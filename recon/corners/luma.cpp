#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

#include "naneye/base/median.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

namespace {

// The scene rule of the defect test (raw_to_luminance's `textured`). A Bayer site's own neighbours
// are 2 px away, where texture seen through a sharp lens may differ from it by anything; its 8
// immediate neighbours (1 px, other colours) share it. So each is brought to the pixel's colour by
// the local colour means (5 x 5, the pixel left out: a grey texture's white balance and a coloured
// one's local hue alike) and the pixel is a defect only if it lies beyond all of them by more than
// the threshold and by more than half their own spread. The half is measured, not derived: on the
// plane, sphere and height presets (Bayer, blur 0.4 px, 30 planted hot, dead and stuck pixels each;
// tests/scene/test_scene_defects.cpp) it repairs 87 of 90 (the board rule 88) and takes 19-29 texture
// pixels per frame for defects (the board rule 305-480); a whole spread took 2-7 texture pixels but
// let a sixth of the planted ones through.
bool apart_from_its_texture(const float* f, int w, int r, int c, bool bayer, float threshold) {
  auto colour = [](int rr, int cc) { return ((rr & 1) * 2 + (cc & 1)) % 3; };  // GRBG: G 0, R 1, B 2
  std::array<double, 3> scale{1, 1, 1};
  if (bayer) {
    std::array<double, 3> sum{}, n{};
    for (int dr = -2; dr <= 2; ++dr)
      for (int dc = -2; dc <= 2; ++dc) {
        if (dr == 0 && dc == 0) continue;
        const int k = colour(r + dr, c + dc);
        sum[static_cast<std::size_t>(k)] += f[(r + dr) * w + c + dc];
        n[static_cast<std::size_t>(k)] += 1;
      }
    const auto own = static_cast<std::size_t>(colour(r, c));
    for (std::size_t k = 0; k < 3; ++k) scale[k] = (sum[own] / n[own]) / std::max(sum[k] / n[k], 1e-3);
  }
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      if (dr == 0 && dc == 0) continue;
      const float b = f[(r + dr) * w + c + dc] *
                      static_cast<float>(scale[static_cast<std::size_t>(colour(r + dr, c + dc))]);
      lo = std::min(lo, b);
      hi = std::max(hi, b);
    }
  const float v = f[r * w + c], t = std::max(threshold, 0.5f * (hi - lo));
  return v > hi + t || v < lo - t;
}

}  // namespace

void raw_to_luminance(const RawImageView& im, float* out, float* scratch, float defect_threshold_dn,
                      int row_lo, int row_hi, const CfaBalance* balance, bool textured) {
  const int w = im.width, h = im.height;
  row_lo = std::clamp(row_lo, 0, h);
  row_hi = row_hi < 0 ? h : std::clamp(row_hi, row_lo, h);
  // The rows the output rows need: the 3x3 filter reads one row more on each side, the defect test
  // of those rows two more (a Bayer site's neighbours).
  const int in_lo = std::max(0, row_lo - 3), in_hi = std::min(h, row_hi + 3);
  const bool bayer = im.layout == PixelLayout::bayer_grbg;
  // Unusable pixels (padding, reference pixels) are replaced by the nearest usable pixel of the same
  // Bayer site (a step of 2 keeps the mosaic phase), so that no filter ever sees them.
  const int step = bayer ? 2 : 1;
  const int col_last = w - 1 - im.ignore_last_cols;
  const int row_first = im.ignore_edge_rows, row_last = h - 1 - im.ignore_edge_rows;
  auto src_col = [&](int c) {
    while (c > col_last) c -= step;
    while (c < 0) c += step;
    return c;
  };
  auto src_row = [&](int r) {
    while (r > row_last) r -= step;
    while (r < row_first) r += step;
    return r;
  };
  float* f = bayer ? scratch : out;
  const int direct = std::min(col_last + 1, w);  // columns read in place
  const int conv_lo = std::max(row_first, in_lo), conv_hi = std::min(row_last + 1, in_hi);
  if (conv_hi > conv_lo && direct > 0) {
    // OpenCV's SIMD conversion for the usable block (headers on our buffers: no allocation).
    const cv::Mat src(conv_hi - conv_lo, direct, CV_16UC1,
                      const_cast<std::uint16_t*>(im.data + static_cast<std::size_t>(conv_lo) * im.stride),
                      static_cast<std::size_t>(im.stride) * sizeof(std::uint16_t));
    cv::Mat dst(src.rows, direct, CV_32FC1, f + conv_lo * w, static_cast<std::size_t>(w) * sizeof(float));
    src.convertTo(dst, CV_32F);
  }
  for (int r = in_lo; r < in_hi; ++r) {
    float* dst = f + r * w;
    if (r < row_first || r > row_last) {
      const std::uint16_t* src = im.data + static_cast<std::size_t>(src_row(r)) * im.stride;
      for (int c = 0; c < direct; ++c) dst[c] = static_cast<float>(src[c]);
    }
    for (int c = direct; c < w; ++c) dst[c] = f[src_row(r) * w + src_col(c)];
  }
  // Defect pixels (hot, dead, stuck; the datasheet allows < 10 per sensor) are replaced by the median
  // of their 8 same-site neighbours. A defect lies beyond all of them by more than the threshold: a
  // blurred board has no such isolated extreme (an edge or corner pixel lies between its neighbours),
  // and the default threshold is ~7 sigma of the shot noise on a white square.
  auto repair = [&](int r, int c) {
    const float v = f[r * w + c];
    std::array<float, 8> nb;
    std::size_t k = 0;
    for (int dr = -step; dr <= step; dr += step) {
      for (int dc = -step; dc <= step; dc += step) {
        if (dr != 0 || dc != 0) nb[k++] = f[(r + dr) * w + c + dc];
      }
    }
    const auto [mn, mx] = std::minmax_element(nb.begin(), nb.end());
    const bool lone = v > *mx + defect_threshold_dn || v < *mn - defect_threshold_dn;
    if (lone && (!textured || apart_from_its_texture(f, w, r, c, bayer, defect_threshold_dn))) {
      f[r * w + c] = base::upper_median(nb);
      return true;
    }
    return false;
  };
  // A defect lies beyond its left and right neighbours: a SIMD pass over a run of the row finds the
  // candidates, the full test runs only on them (and on the pixel after a repaired one, whose left
  // neighbour changed), in raster order like the plain rule.
  constexpr int kRun = 64;
  std::array<float, kRun> beyond;
  using Run = Eigen::Map<const Eigen::Array<float, Eigen::Dynamic, 1>>;
  for (int r = std::max(step, in_lo + step); r < std::min(h - step, in_hi - step); ++r) {
    const float* p = f + r * w;
    int force = -1;  // a column that must be tested whatever its screen value
    for (int c0 = step; c0 < w - step; c0 += kRun) {
      const int m = std::min(kRun, w - step - c0);
      const Run left(p + c0 - step, m), mid(p + c0, m), right(p + c0 + step, m);
      const auto screen = (mid - left.max(right)).max(left.min(right) - mid);
      if (!(screen.maxCoeff() > defect_threshold_dn) && force < c0) continue;  // the usual case
      Eigen::Map<Eigen::Array<float, Eigen::Dynamic, 1>>(beyond.data(), m) = screen;
      for (int j = 0; j < m; ++j) {
        const int c = c0 + j;
        if (!(beyond[static_cast<std::size_t>(j)] > defect_threshold_dn) && c != force) continue;
        if (repair(r, c)) force = c + step;  // its same-site right neighbour now sees the new value
      }
    }
  }
  if (!bayer) return;
  if (balance && balance->valid) {
    // Each site to G-equivalent values (corners/noise.hpp), after the defect test (which compares a
    // pixel with its own site only) and before the filter mixes the sites.
    std::array<float, 4> inv;
    for (std::size_t k = 0; k < 4; ++k) inv[k] = 1.0f / balance->gain[k];
    for (int r = in_lo; r < in_hi; ++r) {
      float* p = f + r * w;
      const std::size_t s0 = static_cast<std::size_t>((r & 1) * 2);
      for (int c = 0; c + 1 < w; c += 2) {
        p[c] = (p[c] - balance->offset[s0]) * inv[s0];
        p[c + 1] = (p[c + 1] - balance->offset[s0 + 1]) * inv[s0 + 1];
      }
      if (w % 2) p[w - 1] = (p[w - 1] - balance->offset[s0]) * inv[s0];
    }
  }
  binomial_3x3(f, out, w, h, row_lo, row_hi);
}

void binomial_3x3(const float* f, float* out, int w, int h, int row_lo, int row_hi) {
  // At the image border the image is mirrored about the pixel (r - 1 -> r + 1: on a mosaic, the same
  // Bayer site).
  auto at = [&](int r, int c) {
    if (r < 0) r = 1;
    if (r >= h) r = h - 2;
    if (c < 0) c = 1;
    if (c >= w) c = w - 2;
    return f[r * w + c];
  };
  auto border = [&](int r, int c) {
    return at(r - 1, c - 1) + 2 * at(r - 1, c) + at(r - 1, c + 1) + 2 * at(r, c - 1) + 4 * at(r, c) +
           2 * at(r, c + 1) + at(r + 1, c - 1) + 2 * at(r + 1, c) + at(r + 1, c + 1);
  };
  for (int r = row_lo; r < row_hi; ++r) {
    float* o = out + r * w;
    if (r == 0 || r == h - 1) {
      for (int c = 0; c < w; ++c) o[c] = border(r, c) * (1.0f / 16.0f);
      continue;
    }
    const float* u = f + (r - 1) * w;
    const float* p = f + r * w;
    const float* d = f + (r + 1) * w;
    o[0] = border(r, 0) * (1.0f / 16.0f);
    // The interior without a branch per pixel, as Eigen arrays (SIMD; the border columns and rows
    // above mirror the mosaic). Same sums in the same order as the scalar formula.
    using Row = Eigen::Map<const Eigen::ArrayXf>;
    const auto m = static_cast<Eigen::Index>(w - 2);
    const Row u0(u, m), u1(u + 1, m), u2(u + 2, m), p0(p, m), p1(p + 1, m), p2(p + 2, m), d0(d, m),
        d1(d + 1, m), d2(d + 2, m);
    Eigen::Map<Eigen::ArrayXf>(o + 1, m) =
        (u0 + 2 * u1 + u2 + 2 * p0 + 4 * p1 + 2 * p2 + d0 + 2 * d1 + d2) * (1.0f / 16.0f);
    o[w - 1] = border(r, w - 1) * (1.0f / 16.0f);
  }
}

}  // namespace naneye::recon
