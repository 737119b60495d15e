#pragma once
// Cubic convolution (Keys, IEEE TASSP 29(6), 1981, a = -0.5) on a float image: the texture here
// reaches wavelengths of ~4 px, where bilinear interpolation's phase error biases a sub-pixel match
// towards whole pixels ("pixel locking": 0.05 px rms measured on the simulator's scenes, noise-free,
// against 0.0x px with this kernel; docs/scene.md). Keys' cubic still locks, by up to 0.018 px in the
// affine LK (tests/scene/test_lk_affine.cpp): the sparse LK and the dense sub-pixel step sample the
// cubic B-spline instead (bspline.hpp, ~10x less); the dense rectification and the feature ids Keys.

#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene {

inline void keys_weights(float t, float* w) {
  const float t2 = t * t, t3 = t2 * t;
  w[0] = -0.5f * t3 + t2 - 0.5f * t;
  w[1] = 1.5f * t3 - 2.5f * t2 + 1.0f;
  w[2] = -1.5f * t3 + 2.0f * t2 + 0.5f * t;
  w[3] = 0.5f * t3 - 0.5f * t2;
}

// The cubic B-spline's weights beta3(t + 1), beta3(t), beta3(t - 1), beta3(t - 2) (bspline.hpp: applied
// to the image's B-spline coefficients they interpolate it). Every vector kernel keeps these
// expressions and their order.
inline void bspline_weights(float t, float* w) {
  const float t2 = t * t, t3 = t2 * t, s = 1.0f - t;
  w[0] = (1.0f / 6.0f) * (s * s * s);
  w[1] = 0.5f * t3 - t2 + (2.0f / 3.0f);
  w[2] = -0.5f * t3 + 0.5f * t2 + 0.5f * t + (1.0f / 6.0f);
  w[3] = (1.0f / 6.0f) * t3;
}

// The 4 x 4 taps from `p` (their top-left, rows `width` apart) weighted by wx, wy: rows top to
// bottom, each row's taps left to right. Every vector kernel (cubic_simd.hpp) keeps this order.
inline float cubic_from_taps(const float* p, int width, const float* wx, const float* wy) {
  float acc = 0;
  for (int i = 0; i < 4; ++i, p += width)
    acc += wy[i] * (wx[0] * p[0] + wx[1] * p[1] + wx[2] * p[2] + wx[3] * p[3]);
  return acc;
}

// The caller keeps (x, y) inside [1, w - 3] x [1, h - 3].
inline float sample_cubic(const GrayView& g, double x, double y) {
  const int c = static_cast<int>(x), r = static_cast<int>(y);
  float wx[4], wy[4];
  keys_weights(static_cast<float>(x - c), wx);
  keys_weights(static_cast<float>(y - r), wy);
  return cubic_from_taps(g.data + (r - 1) * g.width + (c - 1), g.width, wx, wy);
}

// The cubic B-spline at (x, y) over coefficients `c` (bspline_coefficients); the caller keeps (x, y)
// inside [1, w - 3) x [1, h - 3), as for sample_cubic.
inline float sample_bspline(const GrayView& c, float x, float y) {
  const int ci = static_cast<int>(x), ri = static_cast<int>(y);
  float wx[4], wy[4];
  bspline_weights(x - static_cast<float>(ci), wx);
  bspline_weights(y - static_cast<float>(ri), wy);
  return cubic_from_taps(c.data + (ri - 1) * c.width + (ci - 1), c.width, wx, wy);
}

}  // namespace naneye::recon::scene
