#pragma once
// A freshly written .raw capture (the spec's byte stream) with known truth, for the daemon tests:
// alternating left/right records at `fps`, the right sensor `offset_ticks` after the left, and
// pixels that depend on the pair index and the sensor so that served frames can be checked.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include "naneye/driver/wire_format.hpp"

namespace naneye::daemon::test {

struct CaptureTruth {
  int pairs = 0;
  std::uint32_t period_ticks = 0;
  std::uint32_t offset_ticks = 0;
  double fps() const { return static_cast<double>(driver::kTickHz) / period_ticks; }
  std::int64_t period_ns() const {
    return static_cast<std::int64_t>(period_ticks) * 1'000'000'000 / driver::kTickHz;
  }
  std::int64_t offset_ns() const {
    return static_cast<std::int64_t>(offset_ticks) * 1'000'000'000 / driver::kTickHz;
  }
};

// 10-bit value of pixel (row, col) of pair `pair`, sensor 0 (left) or 1 (right). Reference pixels
// follow the spec (row 0: black, saturated, black, saturated; row 249: col 246 black, 247 white).
inline std::uint16_t pixel(int pair, int sensor, int row, int col) {
  if (row == 0 && col < 4) return (col % 2 == 0) ? 40 : 1000;
  if (row == 249 && col == 246) return 30;
  if (row == 249 && col == 247) return 990;
  return static_cast<std::uint16_t>((row * 3 + col * 2 + pair * 5 + sensor * 200) % 1024);
}

inline CaptureTruth write_capture(const std::filesystem::path& file, int pairs, double fps = 62.0,
                                  std::uint32_t offset_ticks = 120'000) {
  CaptureTruth t{pairs, static_cast<std::uint32_t>(static_cast<double>(driver::kTickHz) / fps + 0.5),
                 offset_ticks};
  std::ofstream out(file, std::ios::binary);
  std::vector<std::uint16_t> px(driver::kPixelCount);
  std::vector<std::uint8_t> rec(driver::kRecordSize);
  std::uint8_t seq = 0;
  for (int k = 0; k < pairs; ++k) {
    for (int sensor = 0; sensor < 2; ++sensor) {
      for (int r = 0; r < driver::kSensorSize; ++r)
        for (int c = 0; c < driver::kSensorSize; ++c)
          px[static_cast<std::size_t>(r) * driver::kSensorSize + c] = pixel(k, sensor, r, c);
      const driver::RecordHeader h{
          seq++, sensor == 0 ? driver::Sensor::left : driver::Sensor::right,
          1000 + static_cast<std::uint32_t>(k) * t.period_ticks + (sensor ? offset_ticks : 0)};
      driver::encode_record(
          h, std::span<const std::uint16_t, driver::kPixelCount>(px.data(), driver::kPixelCount),
          std::span<std::uint8_t, driver::kRecordSize>(rec.data(), driver::kRecordSize));
      out.write(reinterpret_cast<const char*>(rec.data()), static_cast<std::streamsize>(rec.size()));
    }
  }
  return t;
}

// The [source] section that replays `file` at its own pace, over and over.
inline std::string looping_source(const std::filesystem::path& file) {
  return "[source]\nuri = \"file://" + file.string() + "?speed=realtime&loop=1\"\n";
}

}  // namespace naneye::daemon::test
