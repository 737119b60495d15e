#pragma once
// A frame is one sensor's record, unpacked; a stereo pair is a left and a right frame paired by
// nearest timestamp (the sensors free-run, so every pair carries its left/right offset).
#include <array>
#include <cstdint>
#include <memory>

#include "naneye/base/enum_table.hpp"
#include "naneye/driver/wire_format.hpp"

namespace naneye::driver {

enum class ColorMode : std::uint8_t { mono, bayer_grbg };

// The spec's reference-pixel sanity check of one frame. `not_checked` when the readout does not
// carry those pixels or the check is off: nothing is claimed (V4L2 grabbers may crop them, so a
// v4l2:// frame is checked only when its URI says `reference=check`).
enum class ReferenceStatus : std::uint8_t { not_checked, passed, failed };

inline constexpr base::EnumTable<ReferenceStatus, 3> kReferenceStatusNames{
    {{ReferenceStatus::not_checked, "not_checked"},
     {ReferenceStatus::passed, "passed"},
     {ReferenceStatus::failed, "failed"}}};

constexpr const char* to_string(ReferenceStatus r) {
  return base::enum_name(kReferenceStatusNames, r, "not_checked");
}

struct Frame {
  Sensor sensor = Sensor::left;
  std::uint8_t seq = 0;
  std::uint32_t ticks = 0;     // as received, 48 MHz, wraps every 89.48 s
  std::uint64_t ticks64 = 0;   // extended across wraps, from the stream's first record
  std::int64_t sensor_ns = 0;  // ticks64 in ns
  std::int64_t host_ns = 0;    // CLOCK_MONOTONIC when the record's last byte arrived
  ReferenceStatus reference = ReferenceStatus::not_checked;
  ColorMode color = ColorMode::mono;
  // 250 x 250, row-major, 10-bit values. Column 249 and row 249 columns 248-249 are padding
  // (see is_padding()); their values are kept as received.
  std::array<std::uint16_t, kPixelCount> pixels{};

  static constexpr bool is_padding(int row, int col) {
    return col == kSensorSize - 1 || (row == kSensorSize - 1 && col >= kSensorSize - 2);
  }
  std::uint16_t at(int row, int col) const {
    return pixels[static_cast<std::size_t>(row) * kSensorSize + col];
  }
};

struct StereoPair {
  std::uint64_t index = 0;  // pairs delivered before this one by the same source
  Frame left, right;
  std::int64_t offset_ns() const { return right.sensor_ns - left.sensor_ns; }
};

// Pairs live in a fixed pool and are handed over by unique ownership; destroying the handle returns
// the buffer to its pool (no allocation per frame). The deleter is supplied by the pool.
struct PairReturn {
  void* pool = nullptr;
  void (*give_back)(void* pool, StereoPair* pair) = nullptr;
  void operator()(StereoPair* p) const {
    if (p && give_back) give_back(pool, p);
  }
};
using PairPtr = std::unique_ptr<StereoPair, PairReturn>;

}  // namespace naneye::driver
