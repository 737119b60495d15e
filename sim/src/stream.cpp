// The sensors' clocks and the raw record stream (spec: Records), with optional damage.
#include "naneye/sim/stream.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <system_error>

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

RawStreamWriter::RawStreamWriter(const std::filesystem::path& file, const FaultSettings& faults,
                                 std::uint64_t fault_seed, std::uint8_t first_seq)
    : faults_(faults), rng_(fault_seed), seq_(first_seq), path_(file) {
  f_ = std::fopen(file.c_str(), "wb");
  if (!f_) throw std::system_error(errno, std::generic_category(), "sim: cannot write " + file.string());
  record_.resize(driver::kRecordSize);
}

RawStreamWriter::~RawStreamWriter() {
  if (f_) std::fclose(f_);
}

RecordFate RawStreamWriter::write(driver::Sensor sensor, std::uint32_t ticks,
                                  std::span<const std::uint16_t, driver::kPixelCount> px) {
  RecordFate fate;
  const driver::RecordHeader h{seq_++, sensor, ticks};  // a lost record still used its seq upstream
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  if (faults_.lost_record_rate > 0 && u01(rng_) < faults_.lost_record_rate) {
    fate.lost = true;
    return fate;
  }
  driver::encode_record(h, px,
                        std::span<std::uint8_t, driver::kRecordSize>(record_.data(), driver::kRecordSize));
  std::size_t size = record_.size();
  // Damage by geometric gaps between events: one draw per event instead of one per byte.
  auto gaps = [&](double rate, auto&& hit) {
    if (rate <= 0) return;
    std::geometric_distribution<std::size_t> gap(rate);
    for (std::size_t i = gap(rng_); i < size; i += 1 + gap(rng_)) hit(i);
  };
  gaps(faults_.bit_flip_rate, [&](std::size_t i) {
    record_[i] ^= static_cast<std::uint8_t>(1u << (rng_() % 8));
    ++fate.bit_flips;
  });
  gaps(faults_.dropped_byte_rate, [&](std::size_t i) {
    record_.erase(record_.begin() + static_cast<std::ptrdiff_t>(i));
    --size;
    ++fate.dropped_bytes;
  });
  if (std::fwrite(record_.data(), 1, size, f_) != size)
    throw std::system_error(errno, std::generic_category(), "sim: write to " + path_.string());
  written_ += size;
  record_.resize(driver::kRecordSize);
  return fate;
}

std::uint64_t RawStreamWriter::finish() {
  if (!f_) return written_;
  if (std::fclose(f_) != 0)
    throw std::system_error(errno, std::generic_category(), "sim: close " + path_.string());
  f_ = nullptr;
  if (faults_.truncate_tail > 0) {
    written_ -= std::min<std::uint64_t>(written_, faults_.truncate_tail);
    std::filesystem::resize_file(path_, written_);
  }
  return written_;
}

}  // namespace naneye::sim
