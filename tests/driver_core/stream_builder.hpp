#pragma once
// Crafted NanEye streams for the tests: records of any sensor size with deterministic pixels
// (valid reference pixels, 10-bit values), built with the wire format's encode_header.
#include <cstdint>
#include <span>
#include <vector>

#include "naneye/driver/frame.hpp"
#include "naneye/driver/stream_parser.hpp"
#include "naneye/driver/wire_format.hpp"

namespace naneye::driver::test {

struct RecordSpec {
  std::uint8_t seq = 0;
  Sensor sensor = Sensor::left;
  std::uint32_t ticks = 0;
};

// Pixel value at index i of a record: depends on seq/sensor so frames are distinguishable.
inline std::uint16_t pixel_value(const RecordSpec& r, int size, std::size_t i) {
  const std::size_t row = i / size, col = i % size;
  if (row == 0 && col < 4) return (col % 2 == 0) ? 40 : 1000;  // black, saturated, black, saturated
  if (row == static_cast<std::size_t>(size - 1) && col == static_cast<std::size_t>(size - 4)) return 30;
  if (row == static_cast<std::size_t>(size - 1) && col == static_cast<std::size_t>(size - 3)) return 990;
  return static_cast<std::uint16_t>((i * 7 + r.seq * 13 + static_cast<int>(r.sensor) * 101 + r.ticks) % 1024);
}

inline void append_record(std::vector<std::uint8_t>& out, const RecordSpec& r, int size = kSensorSize) {
  const std::size_t at = out.size();
  const std::size_t n = static_cast<std::size_t>(size) * size;
  out.resize(at + kHeaderSize + 2 * n);
  encode_header(RecordHeader{r.seq, r.sensor, r.ticks},
                std::span<std::uint8_t, kHeaderSize>(out.data() + at, kHeaderSize));
  std::uint8_t* p = out.data() + at + kHeaderSize;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint16_t v = pixel_value(r, size, i);
    p[2 * i] = static_cast<std::uint8_t>(v & 0xFF);
    p[2 * i + 1] = static_cast<std::uint8_t>(v >> 8);
  }
}

// Alternating left/right records: left at k * period, right offset by `offset` ticks.
inline std::vector<RecordSpec> alternating(int pairs, std::uint8_t first_seq = 0,
                                           std::uint32_t first_ticks = 1000, std::uint32_t period = 1'089'600,
                                           std::int32_t offset = 120'000) {
  std::vector<RecordSpec> v;
  std::uint8_t seq = first_seq;
  for (int k = 0; k < pairs; ++k) {
    const std::uint32_t t = first_ticks + static_cast<std::uint32_t>(k) * period;
    v.push_back({seq++, Sensor::left, t});
    v.push_back({seq++, Sensor::right, t + static_cast<std::uint32_t>(offset)});
  }
  return v;
}

inline std::vector<std::uint8_t> build(const std::vector<RecordSpec>& recs, int size = kSensorSize) {
  std::vector<std::uint8_t> out;
  for (const auto& r : recs) append_record(out, r, size);
  return out;
}

// True if `f` holds exactly the pixels of record `r`.
inline bool frame_matches(const Frame& f, const RecordSpec& r, int size = kSensorSize) {
  if (f.seq != r.seq || f.sensor != r.sensor || f.ticks != r.ticks) return false;
  const std::size_t n = static_cast<std::size_t>(size) * size;
  for (std::size_t i = 0; i < n; ++i)
    if (f.pixels[i] != pixel_value(r, size, i)) return false;
  return true;
}

// A FrameSink that keeps what it receives (tests may allocate).
class CollectingSink : public FrameSink {
 public:
  Frame* begin_frame(const RecordHeader&) override {
    ++begun;
    return &scratch;
  }
  void commit_frame(Frame& f) override { frames.push_back(f); }
  void abort_frame(Frame&) override { ++aborted; }

  Frame scratch;
  std::vector<Frame> frames;
  int begun = 0, aborted = 0;
};

inline ParserSettings small_settings(int size) {
  ParserSettings s;
  s.sensor_size = size;
  return s;
}

}  // namespace naneye::driver::test
