#pragma once
// Pairer: a FrameSink that puts left and right records together by nearest timestamp, without
// copying: when a record's header arrives, the pairer already knows its sensor and time, so it lends
// the parser the empty half of the waiting pair whose other half is nearest in time (within the
// tolerance), or the first half of a fresh pooled pair. A pair is handed over the moment its second
// record completes. Greedy by design: the choice is made at the header, which is exact whenever the
// tolerance is at most half a frame period (then at most one partner can qualify).
//
// 48 MHz ticks are extended to 64 bits relative to the last committed record (signed 32-bit deltas),
// so the 89.48 s wrap is invisible and a bad header cannot derail the timeline. A waiting half
// counts as unpaired (and its buffer goes back) once a frame of the other sensor arrives later than
// its time + tolerance, when more than max_pending halves wait, when time jumps back by over a
// second (a new stream), and at the end of the stream.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "naneye/driver/counters.hpp"
#include "naneye/driver/frame.hpp"
#include "naneye/driver/stream_parser.hpp"

namespace naneye::driver {

struct PairerSettings {
  // Half the nominal frame period (22.7 ms at 2.1 V, the spec's "about 10 ms").
  std::int64_t tolerance_ns = 11'350'000;
  std::size_t max_pending = 4;  // waiting halves per sensor
};

// Where pair buffers come from and where complete pairs go (ByteStreamSource: pool and ring).
class PairChannel {
 public:
  virtual ~PairChannel() = default;
  virtual PairPtr acquire() = 0;  // nullptr: no buffer (the record is skipped)
  virtual void deliver(PairPtr pair) = 0;
};

// Ticks to 64 bits across wraps. After restart() the next record continues the timeline one nominal
// frame later instead (looped replays keep time moving forward).
class TickExtender {
 public:
  std::int64_t peek(std::uint32_t ticks) const {
    if (!started_) return base_;
    return last64_ + static_cast<std::int32_t>(ticks - last32_);
  }
  void commit(std::uint32_t ticks) {
    last64_ = started_ ? peek(ticks) : (have_base_ ? base_ : ticks);
    last32_ = ticks;
    started_ = true;
  }
  void restart() {
    if (started_) {
      base_ = last64_ + static_cast<std::int64_t>(kTickHz / 44);
      have_base_ = true;
    }
    started_ = false;
  }
  std::int64_t peek_first(std::uint32_t ticks) const { return started_ || have_base_ ? peek(ticks) : ticks; }

 private:
  bool started_ = false, have_base_ = false;
  std::uint32_t last32_ = 0;
  std::int64_t last64_ = 0, base_ = 0;
};

inline std::int64_t ticks_to_ns(std::int64_t ticks) {
  return ticks * 125 / 6;
}  // 1e9 / 48e6 = 125 / 6

class Pairer : public FrameSink {
 public:
  Pairer(const PairerSettings& settings, PairChannel& channel, AtomicCounters& counters);

  Frame* begin_frame(const RecordHeader& header) override;
  void commit_frame(Frame& frame) override;
  void abort_frame(Frame& frame) override;

  // End of a stream: every waiting half is unpaired. With `continue_time` the next stream's
  // timeline continues after this one (looped replay); otherwise it restarts from its first record.
  void flush(bool continue_time = false);
  std::size_t waiting() const;

 private:
  struct Slot {
    PairPtr pair;
    std::uint8_t filled = 0;   // bit 0 left, bit 1 right
    std::uint8_t writing = 0;  // the half being written now
    std::int64_t t[2] = {0, 0};
  };
  void expire(std::int64_t t, int sensor);
  void release(Slot& s, bool unpaired);

  PairerSettings settings_;
  PairChannel& channel_;
  AtomicCounters& counters_;
  TickExtender ticks_;
  std::int64_t tolerance_ticks_;
  std::vector<Slot> slots_;  // fixed size: 2 * max_pending + 1
  Slot* current_ = nullptr;
  std::uint64_t next_index_ = 0;
};

}  // namespace naneye::driver
