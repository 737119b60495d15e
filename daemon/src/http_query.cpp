// The daemon's strict reading of client bytes: query numbers and UTF-8. Pure functions (no request,
// no response), apart from the handlers that call them, so that the fuzzer reaches them alone
// (tests/fuzz: http_query).
#include <charconv>
#include <cmath>

#include "http_internal.hpp"

namespace naneye::daemon::http {

std::optional<std::int64_t> strict_int(std::string_view v, std::int64_t lo, std::int64_t hi) {
  // Decimal digits with an optional '-', nothing else: std::stoll also took " 5", "+5" and "5abc"
  // cut short by the caller; from_chars takes no space, no '+', no "0x".
  std::int64_t x = 0;
  const auto* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, x, 10);
  if (v.empty() || ec != std::errc() || p != end || x < lo || x > hi) return std::nullopt;
  return x;
}

std::optional<double> strict_double(std::string_view v) {
  // A plain decimal (or exponent) number: from_chars takes no space and no '+'; "inf", "nan" and
  // hexadecimal ("0x1p3", which it reads as 0 then stops) are refused below.
  double x = 0;
  const auto* end = v.data() + v.size();
  const auto [p, ec] = std::from_chars(v.data(), end, x, std::chars_format::general);
  if (v.empty() || ec != std::errc() || p != end || !std::isfinite(x)) return std::nullopt;
  return x;
}

bool valid_utf8(std::string_view s) {
  // RFC 3629, section 4: no overlong forms, no surrogates, nothing above U+10FFFF.
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const auto* end = p + s.size();
  while (p < end) {
    const unsigned c = *p++;
    if (c < 0x80) continue;
    int more = 0;
    unsigned lo = 0x80, hi = 0xBF;  // the allowed range of the first continuation byte
    if (c >= 0xC2 && c <= 0xDF) {
      more = 1;
    } else if (c >= 0xE0 && c <= 0xEF) {
      more = 2;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      more = 3;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;
    } else {
      return false;
    }
    if (end - p < more) return false;
    if (*p < lo || *p > hi) return false;
    for (int k = 1; k < more; ++k)
      if ((p[k] & 0xC0) != 0x80) return false;
    p += more;
  }
  return true;
}

}  // namespace naneye::daemon::http
