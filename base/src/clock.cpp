#include "naneye/base/clock.hpp"

#include <ctime>

namespace naneye::base {

namespace {

std::int64_t clock_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

std::int64_t monotonic_ns() {
  return clock_ns(CLOCK_MONOTONIC);
}
std::int64_t wall_ns() {
  return clock_ns(CLOCK_REALTIME);
}

}  // namespace naneye::base
