#pragma once
// std::lround without the library call (a libm call per sample was 3 % of the sparse path's
// instructions): half away from zero, like std::lround. v minus its truncation is exact for any
// float or double below 2^31, so the result is std::lround's to the bit. Out of int's range or NaN
// gives INT_MIN, which every caller's bounds test refuses (std::lround's result is unspecified there).
#include <climits>

namespace naneye::recon::scene {

template <class T>
inline int round_half_away(T v) {
  if (!(v > T(INT_MIN + 1) && v < T(INT_MAX - 1))) return INT_MIN;
  const int i = static_cast<int>(v);
  const T f = v - static_cast<T>(i);
  return i + (f >= T(0.5)) - (f <= T(-0.5));
}

}  // namespace naneye::recon::scene
