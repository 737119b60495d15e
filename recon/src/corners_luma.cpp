#include <algorithm>

#include "naneye/recon/corners.hpp"

namespace naneye::recon {

void raw_to_luminance(const RawImageView& im, float* out) {
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
  auto raw = [&](int r, int c) {
    return static_cast<float>(im.data[static_cast<std::size_t>(src_row(r)) * im.stride + src_col(c)]);
  };
  if (!bayer) {
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) out[r * w + c] = raw(r, c);
    }
    return;
  }
  // 3x3 binomial [1 2 1; 2 4 2; 1 2 1] / 16 on the mosaic: at every site it sums R, G, B with
  // weights 1/4, 1/2, 1/4 and it is symmetric about the pixel centre, so edges do not move.
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const bool inner = r > row_first && r < row_last && c > 0 && c < col_last;
      float s;
      if (inner) {
        const std::uint16_t* p = im.data + static_cast<std::size_t>(r) * im.stride + c;
        const std::uint16_t* u = p - im.stride;
        const std::uint16_t* d = p + im.stride;
        s = static_cast<float>(u[-1] + 2 * u[0] + u[1] + 2 * p[-1] + 4 * p[0] + 2 * p[1] + d[-1] + 2 * d[0] +
                               d[1]);
      } else {
        // Borders: mirror about the pixel (r +- 1 -> r -+ 1 is the same Bayer site).
        auto at = [&](int rr, int cc) {
          if (rr < row_first || rr > row_last) rr = 2 * r - rr;
          if (cc < 0 || cc > col_last) cc = 2 * c - cc;
          return raw(rr, cc);
        };
        s = at(r - 1, c - 1) + 2 * at(r - 1, c) + at(r - 1, c + 1) + 2 * at(r, c - 1) + 4 * at(r, c) +
            2 * at(r, c + 1) + at(r + 1, c - 1) + 2 * at(r + 1, c) + at(r + 1, c + 1);
      }
      out[r * w + c] = s * (1.0f / 16.0f);
    }
  }
}

}  // namespace naneye::recon
