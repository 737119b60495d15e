#include "naneye/driver/replay_clock.hpp"

#include <stdexcept>

namespace naneye::driver {

ReplayClock::ReplayClock(double factor) : scale_(1.0 / factor) {
  if (!(factor > 0)) throw std::invalid_argument("ReplayClock: the speed factor must be > 0");
}

ReplayClock::time_point ReplayClock::due(std::int64_t recorded_ns, time_point now) {
  if (!started_) {
    started_ = true;
    first_ns_ = recorded_ns;
    start_ = now;
    return now;
  }
  const auto offset = std::chrono::nanoseconds(
      static_cast<std::int64_t>(static_cast<double>(recorded_ns - first_ns_) * scale_));
  const time_point at = start_ + offset;
  if (now - at <= kHeldAfter) return at;
  start_ += now - at;  // the pass goes on from here at the recorded spacing
  ++resyncs_;
  return now;
}

}  // namespace naneye::driver
