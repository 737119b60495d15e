#pragma once
// The project's one clock for arrival and publication times: CLOCK_MONOTONIC in nanoseconds, the
// clock of Frame::host_ns, of .neyd chunk times and of every *_ns time the daemon publishes.
#include <cstdint>

namespace naneye::base {

std::int64_t monotonic_ns();
// CLOCK_REALTIME in nanoseconds since the epoch: only to label a recording with when it was made
// (it jumps with the system clock, so no duration is ever taken from it).
std::int64_t wall_ns();

}  // namespace naneye::base
