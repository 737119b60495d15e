#pragma once
// The upper median: the element at index size / 2 once ordered (the middle one for an odd count, the
// larger of the middle two for an even one), by nth_element in O(n). Reorders its input: pass a copy
// to keep the order. The recon parts' robust centres (feature motion votes, dark and flat frames,
// calibration checks, the paper's division-model estimate, the corner detector's defect filter,
// lattice step and grid misfit) use this one definition. Header-only, no I/O.
#include <algorithm>
#include <iterator>
#include <ranges>

namespace naneye::base {

// The value type's zero for an empty range.
template <std::ranges::random_access_range R>
std::ranges::range_value_t<R> upper_median(R&& v) {
  if (std::ranges::empty(v)) return {};
  const auto mid = std::ranges::begin(v) + std::ranges::distance(v) / 2;
  std::ranges::nth_element(v, mid);
  return *mid;
}

}  // namespace naneye::base
