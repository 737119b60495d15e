#pragma once
// Time and bytes: the free-running sensors' clocks, and the spec's record stream with optional faults.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <span>
#include <vector>

#include "naneye/driver/wire_format.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {

// The two sensors free-run (spec: 43 to 62 fps, set by the supply voltage, not synchronised): the
// frame period random-walks inside the range, and the right sensor lags the left by an offset that
// drifts slowly, staying under half a period so the nearest-timestamp pairing stays unambiguous.
struct TimingSettings {
  double fps_min = 43.0, fps_max = 62.0;
  double fps_start = 50.0;
  double fps_step = 0.25;   // sd of the per-frame random walk of the frame rate
  double lag_ms_min = 0.5;  // right-after-left offset range
  double lag_ms_max = 8.0;
  double lag_step_ms = 0.05;  // sd of the per-frame random walk of the offset
};

struct PairTime {
  std::uint64_t left_ticks = 0, right_ticks = 0;  // 48 MHz, not wrapped (the records carry the low 32 bits)
  double fps = 0;                                 // the rate this frame was taken at
};

class FrameClock {
 public:
  FrameClock(const TimingSettings& s, std::uint64_t start_ticks, Rng& rng);
  // The times of the next pair (the first call returns start_ticks for the left frame).
  PairTime next(Rng& rng);

 private:
  TimingSettings s_;
  std::uint64_t left_ = 0;
  double fps_ = 0, lag_ms_ = 0;
  bool first_ = true;
};

// Damage for driver tests. Rates are per byte or per record, drawn from the writer's own generator.
struct FaultSettings {
  double bit_flip_rate = 0;       // probability per byte of one flipped bit
  double dropped_byte_rate = 0;   // probability per byte of the byte going missing
  double lost_record_rate = 0;    // probability per record of the record never arriving (seq still advances)
  std::size_t truncate_tail = 0;  // bytes cut off the end of the stream (at most the last record)
  bool any() const {
    return bit_flip_rate > 0 || dropped_byte_rate > 0 || lost_record_rate > 0 || truncate_tail > 0;
  }
};

// What happened to one record on its way out.
struct RecordFate {
  bool lost = false;
  std::uint32_t bit_flips = 0, dropped_bytes = 0;
};

// Where the bytes go: a .raw file, a .neyd container, a source's parser. Called with each piece as
// a USB transfer would deliver it, and the (simulated) host time it arrived.
using ByteSink = std::function<void(std::span<const std::uint8_t> bytes, std::int64_t host_ns)>;

// Encodes records in the spec's format, applies the faults, and hands the bytes to a sink in pieces
// of `chunk_bytes` (a bulk transfer's worth). The last record is held back until finish() so that a
// truncated tail (at most one record's worth) can be cut from it.
class RecordWriter {
 public:
  RecordWriter(ByteSink sink, const FaultSettings& faults, std::uint64_t fault_seed,
               std::uint8_t first_seq = 0, std::size_t chunk_bytes = 16384);
  RecordFate write(driver::Sensor sensor, std::uint32_t ticks,
                   std::span<const std::uint16_t, driver::kPixelCount> px, std::int64_t host_ns);
  // Flushes the held record (minus the truncated tail); returns the bytes handed over in all.
  std::uint64_t finish();

 private:
  void flush();
  ByteSink sink_;
  FaultSettings faults_;
  Rng rng_;
  std::uint8_t seq_;
  std::size_t chunk_;
  std::uint64_t written_ = 0;
  std::vector<std::uint8_t> record_, held_;
  std::int64_t held_ns_ = 0;
  bool holding_ = false;
};

}  // namespace naneye::sim
