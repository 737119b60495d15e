// Where one request ends: the verdict on a request head received so far (http_gate.hpp).
#include <optional>

#include "http_gate.hpp"

namespace naneye::daemon::http {
namespace {

bool iequals_prefix(std::string_view line, std::string_view name) {
  if (line.size() < name.size()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char a = line[i] >= 'A' && line[i] <= 'Z' ? static_cast<char>(line[i] + 32) : line[i];
    if (a != name[i]) return false;
  }
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

}  // namespace

HeadInfo parse_head(std::string_view buf, const GateLimits& limits) {
  HeadInfo info;
  using V = HeadInfo::Verdict;
  const auto eol = buf.find('\n');
  if (eol == std::string_view::npos) {
    if (buf.size() > limits.max_request_line) info.verdict = V::line_too_long;
    return info;
  }
  if (eol > limits.max_request_line) {
    info.verdict = V::line_too_long;
    return info;
  }
  // Header lines up to the blank one (httplib's reader takes "\r\n" or a bare "\n").
  std::size_t pos = eol + 1;
  int headers = 0;
  std::optional<std::size_t> length;
  for (;;) {
    const auto next = buf.find('\n', pos);
    if (next == std::string_view::npos) {
      if (buf.size() > limits.max_head) info.verdict = V::head_too_large;
      return info;
    }
    if (next + 1 > limits.max_head) {
      info.verdict = V::head_too_large;
      return info;
    }
    const std::string_view line = buf.substr(pos, next - pos);
    pos = next + 1;
    if (line.empty() || line == "\r") break;
    if (++headers > limits.max_headers) {
      info.verdict = V::too_many_headers;
      return info;
    }
    if (iequals_prefix(line, "transfer-encoding:")) {
      info.verdict = V::chunked;
      return info;
    }
    if (iequals_prefix(line, "content-length:")) {
      const auto v = trim(line.substr(15));
      std::size_t n = 0;
      // Digits only, and a second Content-Length must agree (RFC 9112, section 6.3).
      if (v.empty() || v.size() > 12) {
        info.verdict = v.empty() ? V::bad_length : V::body_too_large;
        return info;
      }
      for (char c : v) {
        if (c < '0' || c > '9') {
          info.verdict = V::bad_length;
          return info;
        }
        n = n * 10 + static_cast<std::size_t>(c - '0');
      }
      if (length && *length != n) {
        info.verdict = V::bad_length;
        return info;
      }
      length = n;
    }
  }
  info.head_bytes = pos;
  info.body_bytes = length.value_or(0);
  if (info.body_bytes > limits.max_body) {
    info.verdict = V::body_too_large;
    return info;
  }
  if (buf.size() >= info.head_bytes + info.body_bytes) info.verdict = V::complete;
  return info;
}

}  // namespace naneye::daemon::http
