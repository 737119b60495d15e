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

inline std::uint32_t select_bucket(float x) {
  std::uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  return (u & 0x7fffffffu) >> 20;  // -0 sorts with +0
}

// The k-th smallest of v[0, count) given its bucket counts (select_histogram); reorders v, which
// leaves the counts valid for another k.
inline float kth_from_histogram(float* v, std::size_t count, std::size_t k, const SelectHistogram& hist) {
  assert(k < count);  // else the bucket walk runs past the histogram
  std::uint32_t b = 0;
  std::size_t before = 0;
  while (before + hist[b] <= k) before += hist[b++];
  std::size_t m = 0;
  for (std::size_t i = 0; i < count; ++i)
    if (select_bucket(v[i]) == b) std::swap(v[m++], v[i]);
  std::nth_element(v, v + (k - before), v + m);
  return v[k - before];
}

inline void select_histogram(const float* v, std::size_t count, SelectHistogram& hist) {
  hist.fill(0);
  for (std::size_t i = 0; i < count; ++i) ++hist[select_bucket(v[i])];
}

// Reorders v[0, count); requires k < count and every value >= 0 (or -0), none NaN.
inline float kth_smallest(float* v, std::size_t count, std::size_t k, SelectHistogram& hist) {
  select_histogram(v, count, hist);
  return kth_from_histogram(v, count, k, hist);
}

// Two ranks of the same values (a median and a lower quantile) from one counting pass: each the
// value kth_smallest gives (a rank's value does not depend on the order the first left).
inline void kth_smallest_pair(float* v, std::size_t count, std::size_t k1, std::size_t k2,
                              SelectHistogram& hist, float& out1, float& out2) {
  select_histogram(v, count, hist);
  out1 = kth_from_histogram(v, count, k1, hist);
  out2 = kth_from_histogram(v, count, k2, hist);
}

}  // namespace naneye::recon::scene
