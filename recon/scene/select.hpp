#pragma once
// The k-th smallest of non-negative floats, the dense path's medians (residual variances, noise
// correlation factors, depths: ~50 000-100 000 values per pair, three to four medians). Their bit
// patterns order as unsigned integers, so one counting pass over the top bits (the sign masked, the
// exponent, three mantissa bits: 2048 buckets used of the 4096) finds the bucket that holds the k-th value,
// and std::nth_element runs only on that bucket (1/8 of an octave). The value is the one std::nth_element
// over all would give; std::nth_element alone spent ~5 % of the dense path's time in these calls.
#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <cstring>

namespace naneye::recon::scene {

using SelectHistogram = std::array<std::uint32_t, 4096>;

// Reorders v[0, count); requires k < count and every value >= 0 (or -0), none NaN.
inline float kth_smallest(float* v, std::size_t count, std::size_t k, SelectHistogram& hist) {
  assert(k < count);  // else the bucket walk runs past the histogram
  auto bucket = [](float x) {
    std::uint32_t u;
    std::memcpy(&u, &x, sizeof u);
    return (u & 0x7fffffffu) >> 20;  // -0 sorts with +0
  };
  hist.fill(0);
  for (std::size_t i = 0; i < count; ++i) ++hist[bucket(v[i])];
  std::uint32_t b = 0;
  std::size_t before = 0;
  while (before + hist[b] <= k) before += hist[b++];
  std::size_t m = 0;
  for (std::size_t i = 0; i < count; ++i)
    if (bucket(v[i]) == b) std::swap(v[m++], v[i]);
  std::nth_element(v, v + (k - before), v + m);
  return v[k - before];
}

}  // namespace naneye::recon::scene
