// The earlier Gauss-Newton iterations' step (dense_simd.hpp's step_row), in float on whole vectors:
// 4 floats (SSE2) and 8 (AVX2, without FMA), both with the plain float loop's bits
// (DenseKernels.StepRowGivesTheScalarLoopsBits).
#include <algorithm>
#include <limits>

#include "../corners/simd.hpp"
#include "dense_simd.hpp"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace naneye::recon::scene::dense_simd {
namespace {
using simd::kLanes;
using simd::load;
using simd::store;

// The step in the scalar expressions' order, on whole vectors; every branch a select (the lanes
// that fail compute values no output keeps). s[0..8], m: the sums and mask at the block's first pixel.
template <class V>
NANEYE_SIMD_INLINE void step_lanes(const float* const s[9], const float* m_at, const V& d, V& out, V& solved,
                                   V& refused) {
  using VI = simd::VInt<V>;
  const V N = load<V>(s[0]), sw = load<V>(s[1]), sl = load<V>(s[2]), sg = load<V>(s[3]);
  const V inv = 1.f / N;
  const V Sww = load<V>(s[4]) - sw * sw * inv, Sgg = load<V>(s[5]) - sg * sg * inv;
  const V Swg = load<V>(s[6]) - sw * sg * inv, Swl = load<V>(s[7]) - sw * sl * inv;
  const V Sgl = load<V>(s[8]) - sg * sl * inv;
  const V det = Sww * Sgg - Swg * Swg;
  const V na = Sgg * Swl - Swg * Sgl, nc = Swg * Swl - Sww * Sgl;
  const V zero = V{}, one = zero + 1.f, half = zero + 0.5f;
  // d - d is NaN unless d is finite; NaN compares unequal.
  const VI bad = (d - d != zero) | (load<V>(m_at) == zero) | (N < 4.f) | ~(det > zero);
  const VI ok = ~bad & (na > zero);
  V q = nc / det;  // G is the left's gradient (a times the right's): c is the step itself
  q = q < -half ? -half : half < q ? half : q;
  solved = ok ? one : zero;
  refused = bad ? one : zero;
  out = ok ? d + q : zero;
}

template <class V>
NANEYE_SIMD_INLINE void step_row_v(const StepRow& r) {
  constexpr int L = kLanes<V>;
  const V nan = V{} + std::numeric_limits<float>::quiet_NaN();
  int x = r.lo;
  for (; x + L <= r.hi; x += L) {
    const float* s[9];
    for (int k = 0; k < 9; ++k) s[k] = r.s[k] + x;
    V out, solved, refused;
    const V d = load<V>(r.d + x);
    step_lanes<V>(s, r.m + x, d, out, solved, refused);
    store(r.out + x, out);
    store(r.solved + x, solved);
    store(r.d + x, refused > 0.f ? nan : d);
  }
  if (x < r.hi) {  // the tail: the same lanes on a zero-padded copy
    const int count = r.hi - x;
    alignas(32) float buf[11][L] = {};
    const float* s[9];
    for (int k = 0; k < 9; ++k) {
      std::copy(r.s[k] + x, r.s[k] + r.hi, buf[k]);
      s[k] = buf[k];
    }
    std::copy(r.m + x, r.m + r.hi, buf[9]);
    std::copy(r.d + x, r.d + r.hi, buf[10]);
    V out, solved, refused;
    const V d = load<V>(buf[10]);
    alignas(32) float o[L], sv[L], rv[L];
    step_lanes<V>(s, buf[9], d, out, solved, refused);
    store(o, out);
    store(sv, solved);
    store(rv, refused);
    for (int j = 0; j < count; ++j) {
      r.out[x + j] = o[j];
      r.solved[x + j] = sv[j];
      if (rv[j] > 0) r.d[x + j] = std::numeric_limits<float>::quiet_NaN();
    }
  }
}

// The row struct is copied in: every store could write the caller's pointers, which would then be
// reloaded after each one.
void step_row_sse(const StepRow& r) {
  const StepRow copy = r;
  step_row_v<simd::V4>(copy);
}
__attribute__((target("avx2"))) void step_row_avx2(const StepRow& r) {
  const StepRow copy = r;
  step_row_v<simd::V8>(copy);
}
}  // namespace

void step_row(bool avx2, const StepRow& r) {
  (avx2 ? step_row_avx2 : step_row_sse)(r);
}

}  // namespace naneye::recon::scene::dense_simd

#pragma GCC diagnostic pop
