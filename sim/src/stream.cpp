// The sensors' clocks and the raw record stream (spec: Records), with optional damage.
#include "naneye/sim/stream.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace naneye::sim {

FrameClock::FrameClock(const TimingSettings& s, std::uint64_t start_ticks, Rng& rng)
    : s_(s), left_(start_ticks), fps_(std::clamp(s.fps_start, s.fps_min, s.fps_max)) {
  std::uniform_real_distribution<double> lag(s.lag_ms_min, s.lag_ms_max);
  lag_ms_ = lag(rng);
}

PairTime FrameClock::next(Rng& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  if (!first_) {
    fps_ = std::clamp(fps_ + s_.fps_step * n01(rng), s_.fps_min, s_.fps_max);
    left_ += static_cast<std::uint64_t>(std::llround(static_cast<double>(driver::kTickHz) / fps_));
    lag_ms_ = std::clamp(lag_ms_ + s_.lag_step_ms * n01(rng), s_.lag_ms_min, s_.lag_ms_max);
  }
  first_ = false;
  PairTime t;
  t.left_ticks = left_;
  t.right_ticks = left_ + static_cast<std::uint64_t>(std::llround(lag_ms_ * 1e-3 * driver::kTickHz));
  t.fps = fps_;
  return t;
}

RecordWriter::RecordWriter(ByteSink sink, const FaultSettings& faults, std::uint64_t fault_seed,
                           std::uint8_t first_seq, std::size_t chunk_bytes)
    : sink_(std::move(sink)),
      faults_(faults),
      rng_(fault_seed),
      seq_(first_seq),
      chunk_(std::max<std::size_t>(1, chunk_bytes)) {
  record_.reserve(driver::kRecordSize);
  held_.reserve(driver::kRecordSize);
}

RecordFate RecordWriter::write(driver::Sensor sensor, std::uint32_t ticks,
                               std::span<const std::uint16_t, driver::kPixelCount> px, std::int64_t host_ns) {
  RecordFate fate;
  const driver::RecordHeader h{seq_++, sensor, ticks};  // a lost record still used its seq upstream
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  if (faults_.lost_record_rate > 0 && u01(rng_) < faults_.lost_record_rate) {
    fate.lost = true;
    return fate;
  }
  record_.resize(driver::kRecordSize);
  driver::encode_record(h, px,
                        std::span<std::uint8_t, driver::kRecordSize>(record_.data(), driver::kRecordSize));
  // Damage by geometric gaps between events: one draw per event instead of one per byte.
  auto gaps = [&](double rate, auto&& hit) {
    if (rate <= 0) return;
    std::geometric_distribution<std::size_t> gap(rate);
    for (std::size_t i = gap(rng_); i < record_.size(); i += 1 + gap(rng_)) hit(i);
  };
  gaps(faults_.bit_flip_rate, [&](std::size_t i) {
    record_[i] ^= static_cast<std::uint8_t>(1u << (rng_() % 8));
    ++fate.bit_flips;
  });
  gaps(faults_.dropped_byte_rate, [&](std::size_t i) {
    record_.erase(record_.begin() + static_cast<std::ptrdiff_t>(i));
    ++fate.dropped_bytes;
  });
  flush();
  held_.swap(record_);
  held_ns_ = host_ns;
  holding_ = true;
  return fate;
}

void RecordWriter::flush() {
  if (!holding_) return;
  for (std::size_t at = 0; at < held_.size(); at += chunk_) {
    const std::size_t n = std::min(chunk_, held_.size() - at);
    sink_(std::span<const std::uint8_t>(held_.data() + at, n), held_ns_);
  }
  written_ += held_.size();
  holding_ = false;
}

std::uint64_t RecordWriter::finish() {
  if (holding_) held_.resize(held_.size() - std::min(held_.size(), faults_.truncate_tail));
  flush();
  return written_;
}

}  // namespace naneye::sim
