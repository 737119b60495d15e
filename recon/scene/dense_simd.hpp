#pragma once
// The dense sub-pixel step's plane kernels (dense_subpixel.cpp): the window sums and the residual's
// lag filter, written once over a GCC vector type and compiled twice, 4 floats (SSE2, the x86-64
// baseline) and 8 floats (AVX2), chosen at run time as corners/simd.hpp does. They add and multiply
// in the scalar loops' order and never fuse a multiply-add (the AVX2 code is built without FMA), so
// both give the scalar code's bits: the dense results do not depend on the machine.
#include <cstddef>

namespace naneye::recon::scene::dense_simd {

bool avx2_available();

// The rows' spans of left data (RectifiedMatcher::span_lo_, span_hi_): the per-pixel work runs
// only there, ~70 % of the rectified grid (its band columns and the domain disc's corners carry
// nothing).
struct Spans {
  const int *lo, *hi;
  int w, h;
  template <class F>
  void each(F&& f) const {
    for (int y = 0; y < h; ++y)
      for (int x = lo[y]; x < hi[y]; ++x) f(static_cast<std::size_t>(y) * w + x);
  }
};

// Sum over the (2r+1)^2 window (zero outside the image), output inside the spans only (`in` is zero
// outside them); `tmp` holds w floats.
void box_sum(bool avx2, const float* in, float* out, float* tmp, const Spans& sp, int r);

// out += rho * z inside the spans, rho over lags [-lag, lag]^2 (row-major), z zero outside the
// image and the spans.
void filter_lags(bool avx2, const float* z, float* out, const float* rho, int lag, const Spans& sp);

}  // namespace naneye::recon::scene::dense_simd
