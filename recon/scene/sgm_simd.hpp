#pragma once
// The semi-global matcher's row kernels (sgm.cpp), each in three builds: a plain scalar loop (the
// reference), and one written over GCC vector types compiled twice, SSE2 (the x86-64 baseline) and
// AVX2, chosen at run time as dense_simd.hpp does. All arithmetic is on integers (the census
// compares floats, exactly), so every build gives the scalar loops' bits (SgmKernels.* in
// tests/scene/test_sgm.cpp): the disparities do not depend on the machine.
//
// Layouts (all row buffers are indexed by the absolute column x):
//   cost rows (Hamming, box sums, C, S): block x at p + x * D, D values, d = 0 .. D - 1;
//   path rows (L_r): block x at p + x * (D + 2), values at 1 .. D, pads at 0 and D + 1 holding
//   kPad, so that L_r(d - 1) and L_r(d + 1) are plain loads at every d.
#include <cstddef>
#include <cstdint>

namespace naneye::recon::scene::sgm_simd {

enum class Isa { scalar, sse2, avx2 };
Isa best_isa();  // avx2 where the CPU has it, else sse2

// A path value no real one reaches (costs stay below 2^15 / 5, Sgm's constructor checks it): the
// pads' value, so that pad + P1 never wins the minimum and never overflows int16.
inline constexpr std::int16_t kPad = 0x3fff;

// Census transform (Zabih & Woodfill, ECCV 1994) of row y over the 5 x 5 window: bit k set where
// the k-th neighbour (row-major, centre skipped) is brighter than the centre; 0 within 2 px of the
// image's border. Columns [x0, x1) of `out` (the row's w entries).
void census_row(Isa isa, const float* img, std::size_t stride, int w, int h, int y, int x0, int x1,
                std::uint32_t* out);

// Hamming distances between the left census at x and the right one at x - dmin - d:
// H[x * D + d] = popcount(cl[x] ^ cr[w - 1 - x + dmin + d]) for x in [x0, x1), d in [0, D), where
// cr[j] = lo_rev[j] | hi_rev[j] << 16: the right row's census reversed, so that the band is
// contiguous, and split into its low 16 and high 8 bits, so that the kernels count on 16-bit lanes
// (twice the lanes of 32-bit ones, and no narrowing to the 16-bit costs).
void hamming_row(Isa isa, const std::uint32_t* cl, const std::uint16_t* lo_rev, const std::uint16_t* hi_rev,
                 int w, int dmin, int D, int x0, int x1, std::int16_t* H);

// The 3-column sum of a Hamming row: out[x] = H[x - 1] + H[x] + H[x + 1] for x in [x0, x1), the
// neighbours held to [h0, h1) (H is defined there; the pixel itself replaces a missing one).
void hsum3_row(Isa isa, const std::int16_t* H, int D, int h0, int h1, int x0, int x1, std::int16_t* out);

// out = a + b + c over the blocks [x0, x1).
void add3_row(Isa isa, const std::int16_t* a, const std::int16_t* b, const std::int16_t* c, int D, int x0,
              int x1, std::int16_t* out);

// One row of the five paths (sgm.cpp: left to right, top-left, top, top-right, right to left) over
// columns [lo, hi): the paths' values of this row (cur, cur_min for the three from the row above),
// and S = the sum of all five.
struct PathRow {
  const std::int16_t* cost;  // C of this row
  // The row above's paths from top-left, top and top-right and their minima over d, defined on
  // [prev_lo, prev_hi) (empty: no row above; the paths start here).
  const std::int16_t* prev[3];
  const std::int16_t* prev_min[3];
  int prev_lo, prev_hi;
  std::int16_t* cur[3];
  std::int16_t* cur_min[3];
  std::int16_t* horiz[2];  // two path blocks each way (this pixel's and its predecessor's)
  std::int16_t* horiz_back[2];
  const std::int16_t* start;  // a path block of zeros with padded ends: a path's first pixel's predecessor
  std::int16_t* sum;          // S of this row
  int lo, hi, D;
  std::int16_t p1, p2;
};
void aggregate_row(Isa isa, const PathRow& r);

// Winner-take-all on a row of S over [lo, hi), both views (Hirschmueller 2008, Sec. 3.4):
// best[x] = the smallest d of min_d S(x, d); and the right view's along the diagonals, kept
// reversed (right pixel x_r at index w - 1 - x_r, so that a left pixel's band is contiguous):
// rcost_rev, rdisp_rev take S(x, d) and dmin + d where S(x, d) is below what they hold (strictly:
// the first of equal costs, x ascending, d ascending, stays).
void wta_row(Isa isa, const std::int16_t* sum, int D, int dmin, int w, int lo, int hi, std::int16_t* best,
             std::int16_t* rcost_rev, std::int16_t* rdisp_rev);

}  // namespace naneye::recon::scene::sgm_simd
