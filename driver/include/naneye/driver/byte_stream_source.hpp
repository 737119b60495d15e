#pragma once
// ByteStreamSource: the common body of every source that receives the camera's byte stream (usb://,
// v4l2://, file://). A backend implements open() and run(); run() executes on the source's capture
// thread and calls feed() once per transfer as it arrives (host_ns: base::monotonic_ns()). feed() taps the
// raw bytes (recording), then parser -> pairer -> pool buffer -> PairRing -> next(). Counters are atomics,
// snapshotted.
//
// State machine (frame_source.hpp): starting (start() called) -> streaming (set by the base when
// run() begins; backends may move to waiting_for_device / stalled and back to streaming) -> finished
// (run() returned), failed (fail() called) or stopped (stop() called first).
//
// Backends must call stop() in their own destructor: the capture thread calls their virtuals.
#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "naneye/driver/counters.hpp"
#include "naneye/driver/frame_source.hpp"
#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"
#include "naneye/driver/pairer.hpp"
#include "naneye/driver/stream_parser.hpp"

namespace naneye::driver {

struct StreamSettings {
  ParserSettings parser;
  PairerSettings pairer;
  // Pairs waiting for the consumer: 8 is 129 ms at 62 fps. The worker's mean is well under a
  // frame, but a pre-emption or a full search after a lost track can hold it for several frames
  // (with 4, the bundled capture's attack runs dropped 49 and 87 pairs on a VM whose host took
  // 26-48 % of the cores; with 8, 3: docs/reliability.md, "Attacks, 2026-12-03").
  std::size_t ring_capacity = 8;
  std::size_t consumer_hold = 4;  // pairs the consumer may keep at once (pool size = ring + this + pairer)
};

class ByteStreamSource : public FrameSource {
 public:
  // info.live picks the hand-over: true = drop the oldest pair when the ring is full (counted),
  // false = block the capture thread until the consumer takes one (lossless replay).
  ByteStreamSource(SourceInfo info, StreamSettings settings);
  ~ByteStreamSource() override;

  void start() override;
  void stop() override;
  PairPtr next(std::chrono::milliseconds timeout) override;
  SourceState state() const override { return state_.load(std::memory_order_acquire); }
  SourceCounters counters() const override;
  SourceInfo info() const override { return info_; }
  std::optional<std::string> error() const override;
  bool set_raw_tap(RawTap* tap) override;

 protected:
  virtual void open() {}       // on the caller's thread inside start(); throw SourceError on failure
  virtual void run() = 0;      // the capture thread: return at end of data, or soon after stopping()
  virtual void interrupt() {}  // from stop(), any thread: unblock run() (e.g. cancel transfers)
  // A record with this sensor time (ns, 64-bit timeline) starts being unpacked, on the capture
  // thread; replay paces .raw files here so each record completes at its own time.
  virtual void on_record_start(std::int64_t sensor_ns) { (void)sensor_ns; }

  // For run():
  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_ns);  // one transfer as received
  // The stream ended or broke (device lost, end of file pass): a record in progress is cut, waiting
  // halves are unpaired. With `continue_time` the next stream continues the timeline (looping).
  void end_of_stream(std::int64_t host_ns, bool continue_time = false);
  bool stopping() const { return stop_.load(std::memory_order_acquire); }
  // Sleeps until `deadline` or stop(); false if stopped.
  bool sleep_until(std::chrono::steady_clock::time_point deadline);
  void set_state(SourceState s) { state_.store(s, std::memory_order_release); }
  void fail(std::string message);       // state failed, error() = message
  void set_error(std::string message);  // error() without changing the state
  AtomicCounters& live_counters() { return counters_; }
  std::uint64_t records_committed() const { return records_.load(std::memory_order_relaxed); }

 private:
  class Channel;
  class TimingSink;
  void thread_main();

  SourceInfo info_;
  AtomicCounters counters_;
  PairPool pool_;
  PairRing ring_;
  std::unique_ptr<Channel> channel_;
  std::unique_ptr<TimingSink> timing_;
  std::unique_ptr<Pairer> pairer_;
  std::unique_ptr<StreamParser> parser_;
  RawTap* tap_ = nullptr;

  std::atomic<SourceState> state_{SourceState::starting};
  std::atomic<bool> stop_{false};
  std::atomic<bool> started_{false};
  std::atomic<std::uint64_t> records_{0};
  mutable std::mutex error_mutex_;
  std::optional<std::string> error_;
  std::mutex sleep_mutex_;
  std::condition_variable sleep_cv_;
  std::thread thread_;
};

}  // namespace naneye::driver
