#include "naneye/driver/wire_format.hpp"

namespace naneye::driver {

std::optional<RecordHeader> decode_header(std::span<const std::uint8_t, kHeaderSize> b) {
  if ((b[1] & 0xF0) != 0xB0 || b[2] != 0xFE || b[3] != 0xCA) return std::nullopt;
  const std::uint8_t sid = b[1] & 0x0F;
  if (sid > 1) return std::nullopt;
  RecordHeader h;
  h.seq = b[0];
  h.sensor = static_cast<Sensor>(sid);
  h.ticks = static_cast<std::uint32_t>(b[4]) | static_cast<std::uint32_t>(b[5]) << 8 |
            static_cast<std::uint32_t>(b[6]) << 16 | static_cast<std::uint32_t>(b[7]) << 24;
  return h;
}

void encode_header(const RecordHeader& h, std::span<std::uint8_t, kHeaderSize> out) {
  out[0] = h.seq;
  out[1] = static_cast<std::uint8_t>(0xB0 | static_cast<std::uint8_t>(h.sensor));
  out[2] = 0xFE;
  out[3] = 0xCA;
  for (int i = 0; i < 4; ++i) out[4 + i] = static_cast<std::uint8_t>(h.ticks >> (8 * i));
}

void encode_record(const RecordHeader& h, std::span<const std::uint16_t, kPixelCount> pixels,
                   std::span<std::uint8_t, kRecordSize> out) {
  encode_header(h, out.first<kHeaderSize>());
  std::uint8_t* p = out.data() + kHeaderSize;
  for (std::uint16_t v : pixels) {
    *p++ = static_cast<std::uint8_t>(v & 0xFF);
    *p++ = static_cast<std::uint8_t>(v >> 8);
  }
}

}  // namespace naneye::driver
