#pragma once
// The dense path's rectification per pair (RectifiedRig::resample, dense_rectify.hpp): every
// rectified pixel is Keys' cubic of the raw image at its precomputed tap and fractional offsets.
// The plain loop is the reference; 4 lanes (SSE2, the x86-64 baseline) and 8 (AVX2 with its gather
// instruction, chosen at run time) give its bits, computing the same expressions in the same order.
#include <cstddef>

namespace naneye::recon::scene::resample {

// out[i] = sum_r wy_r(fy[i]) sum_c wx_c(fx[i]) raw[tap[i] + (r - 1) raw_width + c - 1], r, c in 0..3
// (Keys' weights); 0 where tap[i] < 0. Every valid tap's 4 x 4 neighbourhood lies inside `raw`.
void taps(const float* raw, int raw_width, const int* tap, const float* fx, const float* fy, std::size_t n,
          float* out);
// One width: 1 (the plain loop), 4, or 8 (AVX2 machines only); for tests.
void taps_lanes(int lanes, const float* raw, int raw_width, const int* tap, const float* fx, const float* fy,
                std::size_t n, float* out);

}  // namespace naneye::recon::scene::resample
