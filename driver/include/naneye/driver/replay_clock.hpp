#pragma once
// ReplayClock: when a replayed record is due. A pass keeps its records' recorded spacing (divided by
// the speed factor) from its first record, which is due at once.
//
// A record found due more than kHeldAfter in the past means the replay thread was held (a loaded
// machine pre-empted it), not that the recording was fast. A camera never delivers the frames of
// such a gap at once: its frames keep their spacing whatever the host does. So the pass is moved
// later by the gap and goes on at the recorded spacing from that record; releasing the late records
// together instead would fill the consumer's ring in a burst and drop pairs no camera would cost.
#include <chrono>
#include <cstdint>

namespace naneye::driver {

class ReplayClock {
 public:
  using time_point = std::chrono::steady_clock::time_point;
  // A record of a 62 fps camera is 16.1 ms behind the previous one: one found later than this was
  // held, not jittered (a loaded machine's wake-up latency is well below it).
  static constexpr std::chrono::milliseconds kHeldAfter{20};

  // `factor`: recorded time is divided by it (1 = real time); > 0.
  explicit ReplayClock(double factor = 1.0);

  // A new pass: its first record is due when it is asked for.
  void restart() { started_ = false; }
  // When the record recorded at `recorded_ns` (any epoch, the pass's own) is due, `now` being the
  // present. Asked once per record, in recorded order.
  time_point due(std::int64_t recorded_ns, time_point now);
  // How many times a held replay was moved later (each by its own gap).
  std::uint64_t resyncs() const { return resyncs_; }

 private:
  double scale_;
  bool started_ = false;
  std::int64_t first_ns_ = 0;
  time_point start_{};
  std::uint64_t resyncs_ = 0;
};

}  // namespace naneye::driver
