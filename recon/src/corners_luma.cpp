#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>

#include "naneye/recon/corners.hpp"

namespace naneye::recon {

void raw_to_luminance(const RawImageView& im, float* out, float* scratch, float defect_threshold_dn) {
  const int w = im.width, h = im.height;
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
  for (int r = 0; r < h; ++r) {
    const std::uint16_t* src = im.data + static_cast<std::size_t>(src_row(r)) * im.stride;
    float* dst = f + r * w;
    const int direct = std::min(col_last + 1, w);  // columns read in place (no branch: vectorises)
    for (int c = 0; c < direct; ++c) dst[c] = static_cast<float>(src[c]);
    for (int c = direct; c < w; ++c) dst[c] = static_cast<float>(src[src_col(c)]);
  }
  // Defect pixels (hot, dead, stuck; the datasheet allows < 10 per sensor) are replaced by the median
  // of their 8 same-site neighbours. A defect lies beyond all of them by more than the threshold: a
  // blurred board has no such isolated extreme (an edge or corner pixel lies between its neighbours),
  // and the default threshold is ~7 sigma of the shot noise on a white square.
  using Row = Eigen::Map<const Eigen::ArrayXf>;
  const auto inner = static_cast<Eigen::Index>(w - 2 * step);
  for (int r = step; r < h - step; ++r) {
    // A defect lies beyond its left and right neighbours: one SIMD pass over the row rules out
    // almost every row, the scalar test below runs only where that pass found a candidate.
    const float* p = f + r * w;
    const Row left(p, inner), mid(p + step, inner), right(p + 2 * step, inner);
    const float beyond = (mid - left.max(right)).max(left.min(right) - mid).maxCoeff();
    if (!(beyond > defect_threshold_dn)) continue;
    for (int c = step; c < w - step; ++c) {
      const float v = f[r * w + c];
      // A defect lies beyond every neighbour, so one neighbour within the threshold clears it.
      if (std::abs(v - f[r * w + c - step]) <= defect_threshold_dn) continue;
      std::array<float, 8> nb;
      std::size_t k = 0;
      for (int dr = -step; dr <= step; dr += step) {
        for (int dc = -step; dc <= step; dc += step) {
          if (dr != 0 || dc != 0) nb[k++] = f[(r + dr) * w + c + dc];
        }
      }
      const auto [mn, mx] = std::minmax_element(nb.begin(), nb.end());
      if (v > *mx + defect_threshold_dn || v < *mn - defect_threshold_dn) {
        std::nth_element(nb.begin(), nb.begin() + 4, nb.end());
        f[r * w + c] = nb[4];
      }
    }
  }
  if (!bayer) return;
  // 3x3 binomial [1 2 1; 2 4 2; 1 2 1] / 16 on the mosaic: at every site it sums R, G, B with
  // weights 1/4, 1/2, 1/4 and it is symmetric about the pixel centre, so edges do not move. At the
  // image border the mosaic is mirrored about the pixel (r - 1 -> r + 1 is the same Bayer site).
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
  for (int r = 0; r < h; ++r) {
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
