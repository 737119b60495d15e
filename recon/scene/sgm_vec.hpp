#pragma once
// The vector types and helpers the semi-global matcher's kernels share (sgm_simd.cpp: census,
// Hamming, sums, winner-take-all; sgm_paths.cpp: the paths). Everything here is inlined into the
// kernels' entry points, each compiled for its own target (SSE2, AVX2).
#include <cstdint>
#include <cstring>

// The 32-byte helpers run only inlined into AVX2 functions, never across a call boundary whose ABI
// would depend on the target; GCC reports them at the end of the unit, so the note stays off to
// its end (as in corners/simd.cpp).
#pragma GCC diagnostic ignored "-Wpsabi"

#define NANEYE_SGM_INLINE inline __attribute__((always_inline))

namespace naneye::recon::scene::sgm_simd::vec {

// One vector width's types: floats and 32-bit lanes (census), and 16-bit lanes (Hamming, costs).
// (GCC takes vector_size only with a constant, not a template parameter: one specialisation each.)
template <int Bytes>
struct Vec;
template <>
struct Vec<16> {
  using F = float __attribute__((vector_size(16)));
  using U = std::uint32_t __attribute__((vector_size(16)));
  using H = std::int16_t __attribute__((vector_size(16)));
  using UH = std::uint16_t __attribute__((vector_size(16)));
  using HalfH = std::int16_t __attribute__((vector_size(8)));  // U's lanes narrowed
  static constexpr int k32 = 4, k16 = 8;
};
template <>
struct Vec<32> {
  using F = float __attribute__((vector_size(32)));
  using U = std::uint32_t __attribute__((vector_size(32)));
  using H = std::int16_t __attribute__((vector_size(32)));
  using UH = std::uint16_t __attribute__((vector_size(32)));
  using HalfH = std::int16_t __attribute__((vector_size(16)));
  static constexpr int k32 = 8, k16 = 16;
};

template <class T, class P>
NANEYE_SGM_INLINE T load(const P* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <class T, class P>
NANEYE_SGM_INLINE void store(P* p, const T& v) {
  std::memcpy(p, &v, sizeof v);
}
template <class T>
NANEYE_SGM_INLINE T vmin(const T& a, const T& b) {
  return a < b ? a : b;
}

// The smallest lane, by halving: each step takes the lane-wise minimum with the other half.
template <int B>
NANEYE_SGM_INLINE int hmin(const typename Vec<B>::H& in) {
  using V = typename Vec<B>::H;
  V v = in;
  if constexpr (B == 32) {
    v = vmin(v, __builtin_shuffle(v, V{8, 9, 10, 11, 12, 13, 14, 15, 0, 1, 2, 3, 4, 5, 6, 7}));
    v = vmin(v, __builtin_shuffle(v, V{4, 5, 6, 7, 0, 1, 2, 3, 12, 13, 14, 15, 8, 9, 10, 11}));
    v = vmin(v, __builtin_shuffle(v, V{2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14}));
  } else {
    v = vmin(v, __builtin_shuffle(v, V{4, 5, 6, 7, 0, 1, 2, 3}));
    v = vmin(v, __builtin_shuffle(v, V{2, 3, 0, 1, 6, 7, 4, 5}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6}));
  }
  return v[0];
}

// The smallest lanes of four vectors in one reduction: each halving step takes the minimum of two
// vectors' halves packed side by side, so the four reductions share their shuffles and minima
// (8 steps of shuffle + minimum at 16 lanes instead of 16; min is exact, the same bits).
template <int B>
NANEYE_SGM_INLINE void hmin4(const typename Vec<B>::H& a, const typename Vec<B>::H& b,
                             const typename Vec<B>::H& c, const typename Vec<B>::H& d, int out[4]) {
  using V = typename Vec<B>::H;
  if constexpr (B == 32) {
    // 128-bit halves: [a | b] and [c | d], each 8 lanes (vperm2i128).
    const V ab =
        vmin(__builtin_shuffle(a, b, V{0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23}),
             __builtin_shuffle(a, b, V{8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31}));
    const V cd =
        vmin(__builtin_shuffle(c, d, V{0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23}),
             __builtin_shuffle(c, d, V{8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31}));
    // 64-bit quarters within each 128-bit half (punpck[lh]qdq): [a 4, c 4 | b 4, d 4].
    V v = vmin(__builtin_shuffle(ab, cd, V{0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27}),
               __builtin_shuffle(ab, cd, V{4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31}));
    v = vmin(v, __builtin_shuffle(v, V{2, 3, 0, 1, 6, 7, 4, 5, 10, 11, 8, 9, 14, 15, 12, 13}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6, 9, 8, 11, 10, 13, 12, 15, 14}));
    out[0] = v[0];
    out[1] = v[8];
    out[2] = v[4];
    out[3] = v[12];
  } else {
    // 64-bit halves (punpck[lh]qdq): [a 4, b 4] and [c 4, d 4].
    const V ab = vmin(__builtin_shuffle(a, b, V{0, 1, 2, 3, 8, 9, 10, 11}),
                      __builtin_shuffle(a, b, V{4, 5, 6, 7, 12, 13, 14, 15}));
    const V cd = vmin(__builtin_shuffle(c, d, V{0, 1, 2, 3, 8, 9, 10, 11}),
                      __builtin_shuffle(c, d, V{4, 5, 6, 7, 12, 13, 14, 15}));
    // 32-bit pairs (shufps): [a 2, b 2, c 2, d 2].
    V v = vmin(__builtin_shuffle(ab, cd, V{0, 1, 4, 5, 8, 9, 12, 13}),
               __builtin_shuffle(ab, cd, V{2, 3, 6, 7, 10, 11, 14, 15}));
    v = vmin(v, __builtin_shuffle(v, V{1, 0, 3, 2, 5, 4, 7, 6}));
    out[0] = v[0];
    out[1] = v[2];
    out[2] = v[4];
    out[3] = v[6];
  }
}

}  // namespace naneye::recon::scene::sgm_simd::vec
