// Saddle candidates for the full-search coarse grid (corners_coarse.hpp): the Hessian determinant
// of a lightly smoothed luminance, 5x5 non-maximum suppression, a quadratic sub-pixel peak and a
// ring test. Hand-written rather than cv::GaussianBlur / cv::Sobel because OpenCV's filter engine
// allocates on every call and the daemon must not allocate per frame.
#include <algorithm>
#include <array>
#include <cmath>

#include "naneye/recon/corners_coarse.hpp"

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

CoarseGridFinder::CoarseGridFinder(int width, int height, const CoarseGridSettings& settings)
    : s_(settings), width_(width), height_(height) {
  const auto n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  tmp_.assign(n, 0.0f);
  smooth_.assign(n, 0.0f);
  resp_.assign(n, 0.0f);
  cand_.resize(kCandidateCapacity);
  order_.resize(kCandidateCapacity);
  cell_of_.resize(kCandidateCapacity);
  grid_.resize(static_cast<std::size_t>(kMaxSide) * kMaxSide);
}

void CoarseGridFinder::saddle_map(const LumaView& img) {
  // Binomial [1 4 6 4 1] / 16 (sigma = 1 px) in both directions, reads clamped to the usable area,
  // then -det(H) from central differences: a saddle has det < 0 at its centre, an edge det ~ 0.
  const int w = width_, rb = img.row_begin, re = img.row_end, ce = img.col_end;
  const float k0 = 6.0f / 16, k1 = 4.0f / 16, k2 = 1.0f / 16;
  for (int r = rb; r < re; ++r) {
    const float* in = img.data + r * w;
    float* o = tmp_.data() + r * w;
    for (int c = 0; c < ce; ++c) {
      if (c >= 2 && c + 2 < ce) {
        o[c] = k0 * in[c] + k1 * (in[c - 1] + in[c + 1]) + k2 * (in[c - 2] + in[c + 2]);
      } else {
        auto at = [&](int cc) { return in[std::clamp(cc, 0, ce - 1)]; };
        o[c] = k0 * at(c) + k1 * (at(c - 1) + at(c + 1)) + k2 * (at(c - 2) + at(c + 2));
      }
    }
  }
  for (int r = rb; r < re; ++r) {
    const float* m2 = tmp_.data() + std::max(r - 2, rb) * w;
    const float* m1 = tmp_.data() + std::max(r - 1, rb) * w;
    const float* m0 = tmp_.data() + r * w;
    const float* p1 = tmp_.data() + std::min(r + 1, re - 1) * w;
    const float* p2 = tmp_.data() + std::min(r + 2, re - 1) * w;
    float* o = smooth_.data() + r * w;
    for (int c = 0; c < ce; ++c) o[c] = k0 * m0[c] + k1 * (m1[c] + p1[c]) + k2 * (m2[c] + p2[c]);
  }
  std::fill(resp_.begin(), resp_.end(), 0.0f);
  for (int r = rb + 1; r + 1 < re; ++r) {
    const float* a = smooth_.data() + (r - 1) * w;
    const float* m = smooth_.data() + r * w;
    const float* b = smooth_.data() + (r + 1) * w;
    float* o = resp_.data() + r * w;
    for (int c = 1; c + 1 < ce; ++c) {
      const float ixx = m[c - 1] - 2 * m[c] + m[c + 1];
      const float iyy = a[c] - 2 * m[c] + b[c];
      const float ixy = 0.25f * (b[c + 1] - b[c - 1] - a[c + 1] + a[c - 1]);
      o[c] = ixy * ixy - ixx * iyy;
    }
  }
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
  return h2 >= s_.min_harmonic_ratio * h1 && h2 * (2.0f / 16) >= s_.min_ring_amplitude_dn;
}

void CoarseGridFinder::collect_candidates(const LumaView& img) {
  const int w = width_;
  float peak = 0;
  for (int r = img.row_begin; r < img.row_end; ++r) {
    for (int c = 0; c < img.col_end; ++c) peak = std::max(peak, resp_[static_cast<std::size_t>(r * w + c)]);
  }
  count_ = 0;
  if (!(peak > 0)) return;
  const float threshold = s_.min_relative_response * peak;
  for (int r = img.row_begin + 2; r + 2 < img.row_end; ++r) {
    for (int c = 2; c + 2 < img.col_end; ++c) {
      const float* p = resp_.data() + r * w + c;
      const float v = *p;
      if (v < threshold) continue;
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
      if (++count_ == kCandidateCapacity) return;
    }
  }
}

}  // namespace naneye::recon
