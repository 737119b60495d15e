#pragma once
// The NanEye Stereo record layout of ../shared/spec/naneye-stream.md (the contract for .raw dumps):
//   0: seq (u8, +1 per record across both sensors)   1: 0xB0 | sensor id   2..3: FE CA
//   4..7: timestamp, u32 LE, 48 MHz ticks            8..: width x height pixels, u16 LE, 10-bit
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace naneye::driver {

inline constexpr std::size_t kHeaderSize = 8;
inline constexpr int kSensorSize = 250;  // pixels per side of the NanEye 2D die
inline constexpr std::size_t kPixelCount = static_cast<std::size_t>(kSensorSize) * kSensorSize;
inline constexpr std::size_t kRecordSize = kHeaderSize + 2 * kPixelCount;  // 125 008 bytes
inline constexpr std::uint64_t kTickHz = 48'000'000;
inline constexpr std::uint16_t kPixelMax = 1023;

enum class Sensor : std::uint8_t { left = 0, right = 1 };

struct RecordHeader {
  std::uint8_t seq = 0;
  Sensor sensor = Sensor::left;
  std::uint32_t ticks = 0;
};

// Header test of the spec: b[1] & 0xF0 == 0xB0, b[2] == 0xFE, b[3] == 0xCA. Sensor ids other than 0
// and 1 are not NanEye Stereo records and are refused.
std::optional<RecordHeader> decode_header(std::span<const std::uint8_t, kHeaderSize> bytes);
void encode_header(const RecordHeader& h, std::span<std::uint8_t, kHeaderSize> out);

// Writes one whole record (header + pixels, row-major u16 LE) into `out` (kRecordSize bytes).
void encode_record(const RecordHeader& h, std::span<const std::uint16_t, kPixelCount> pixels,
                   std::span<std::uint8_t, kRecordSize> out);

}  // namespace naneye::driver
