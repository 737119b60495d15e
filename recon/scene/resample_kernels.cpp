// See resample_kernels.hpp. Callgrind, one mono plane pair: the two eyes' rectification took 19 M
// of the dense path's instructions in the plain loop (the weights and 16 scalar products per pixel).
#include "resample_kernels.hpp"

#include <immintrin.h>

#include "../corners/simd.hpp"
#include "cubic_simd.hpp"
#include "interpolate.hpp"

namespace naneye::recon::scene::resample {
namespace {
using simd::kLanes;
using simd::load;
using simd::store;
using VI4 = simd::VI4;

// The reference, and every width's tail.
void taps_plain(const float* raw, int raw_width, const int* tap, const float* fx, const float* fy,
                std::size_t i0, std::size_t n, float* out) {
  for (std::size_t i = i0; i < n; ++i) {
    if (tap[i] < 0) {
      out[i] = 0.f;
      continue;
    }
    float wx[4], wy[4];
    keys_weights(fx[i], wx);
    keys_weights(fy[i], wy);
    out[i] = cubic_from_taps(raw + tap[i] - raw_width - 1, raw_width, wx, wy);
  }
}

void taps_sse(const float* raw, int raw_width, const int* tap, const float* fx, const float* fy,
              std::size_t n, float* out) {
  using V = simd::V4;
  constexpr std::size_t L = kLanes<V>;
  // An invalid lane reads the first 4 x 4 taps of the image (always there) and is zeroed after.
  const VI4 safe = VI4{} + (raw_width + 1), back = VI4{} + (raw_width + 1);
  std::size_t i = 0;
  for (; i + L <= n; i += L) {
    VI4 t;
    __builtin_memcpy(&t, tap + i, sizeof t);
    const VI4 valid = t >= 0;
    const VI4 idx = (valid ? t : safe) - back;
    V wx[4], wy[4];
    keys_v<V>(load<V>(fx + i), wx);
    keys_v<V>(load<V>(fy + i), wy);
    store(out + i, valid ? cubic_from_taps_v<V>(raw, idx, raw_width, wx, wy) : V{} + 0.f);
  }
  taps_plain(raw, raw_width, tap, fx, fy, i, n, out);
}

__attribute__((target("avx2"))) void taps_avx2(const float* raw, int raw_width, const int* tap,
                                               const float* fx, const float* fy, std::size_t n, float* out) {
  const __m256i back = _mm256_set1_epi32(raw_width + 1);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    const __m256i t = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(tap + i));
    const __m256i invalid = _mm256_cmpgt_epi32(_mm256_setzero_si256(), t);
    // An invalid lane reads the first 4 x 4 taps of the image (always there) and is zeroed after.
    const __m256i idx = _mm256_sub_epi32(_mm256_blendv_epi8(t, back, invalid), back);
    __m256 wx[4], wy[4];
    keys8(_mm256_loadu_ps(fx + i), wx);
    keys8(_mm256_loadu_ps(fy + i), wy);
    const __m256 acc = cubic_from_taps8(raw, idx, raw_width, wx, wy);
    _mm256_storeu_ps(out + i, _mm256_andnot_ps(_mm256_castsi256_ps(invalid), acc));
  }
  taps_plain(raw, raw_width, tap, fx, fy, i, n, out);
}
}  // namespace

void taps(const float* raw, int raw_width, const int* tap, const float* fx, const float* fy, std::size_t n,
          float* out) {
  (simd::has_avx2() ? taps_avx2 : taps_sse)(raw, raw_width, tap, fx, fy, n, out);
}

void taps_lanes(int lanes, const float* raw, int raw_width, const int* tap, const float* fx, const float* fy,
                std::size_t n, float* out) {
  if (lanes == 8) return taps_avx2(raw, raw_width, tap, fx, fy, n, out);
  if (lanes == 4) return taps_sse(raw, raw_width, tap, fx, fy, n, out);
  taps_plain(raw, raw_width, tap, fx, fy, 0, n, out);
}

}  // namespace naneye::recon::scene::resample
