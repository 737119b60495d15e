#pragma once
// The semi-global matcher's scalar row kernels (sgm_scalar.cpp): the reference the vector builds in
// sgm_simd.cpp are tested against (SgmKernels.*), and the plain loops those use for border columns.
// Each one's contract is its entry point's in sgm_simd.hpp.
#include <cstddef>
#include <cstdint>

#include "sgm_simd.hpp"

namespace naneye::recon::scene::sgm_simd::scalar {

inline constexpr int kCensusR = 2;  // px; the 5 x 5 census window's radius

void census(const float* img, std::size_t stride, int w, int h, int y, int x0, int x1, std::uint32_t* out);
void hamming(const std::uint32_t* cl, const std::uint16_t* lo_rev, const std::uint16_t* hi_rev, int w,
             int dmin, int D, int x0, int x1, std::int16_t* H);
void hsum3(const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out);
void add3(const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0, int x1,
          std::int16_t* out);
void aggregate(const PathRow& r);
void wta(const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
         std::int16_t* rcost_rev, std::int16_t* rdisp_rev);

// The row's pixel x's predecessor along a path from the row above at column xp, or the start block
// (a path's first pixel: Eq. 13 with a zero predecessor).
struct Pred {
  const std::int16_t* block;
  int min;
};
inline __attribute__((always_inline)) Pred above(const PathRow& r, int k, int xp) {
  const int Ds = r.D + 2;
  if (xp < r.prev_lo || xp >= r.prev_hi) return {r.start, 0};
  return {r.prev[k] + static_cast<std::size_t>(xp) * Ds, r.prev_min[k][xp]};
}

}  // namespace naneye::recon::scene::sgm_simd::scalar
