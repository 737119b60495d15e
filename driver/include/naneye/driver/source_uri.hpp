#pragma once
// Source URIs, parsed once into plain structs; every refusal is a SourceError that names the
// offending parameter and what it accepts.
//   usb://10f8:c487[?serial=...&interface=0&endpoint=0x86]
//   v4l2:///dev/video0[?layout=side-by-side|top-bottom|alternate&format=Y10|Y16|GREY|SGRBG10]
//   file:///path/capture.raw | .neyd [?speed=realtime|max|<factor>&loop=0|1&chunk=<bytes>]
//   sim://...  (parsed generically here; its parameters belong to the simulator)
// A string without "scheme://" is a file path. Every byte-stream scheme also takes the stream
// parameters color=mono|grbg, tolerance_ms=<ms>, reference=check|reject|off.
#include <array>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "naneye/driver/byte_stream_source.hpp"

namespace naneye::driver {

struct SourceUri {
  std::string text;    // as given
  std::string scheme;  // lower case: "usb", "v4l2", "file", "sim", ...
  std::string target;  // between "://" and "?", percent-decoded: "10f8:c487", "/dev/video0", a path
  std::vector<std::pair<std::string, std::string>> params;  // in order, percent-decoded

  std::optional<std::string> param(std::string_view name) const;
  // Throws SourceError for the first parameter not in `accepted` (listing them).
  void allow_only(std::initializer_list<std::string_view> accepted) const;
};

SourceUri parse_uri(std::string_view text);

// The stream parameters above, applied on top of `defaults`.
inline constexpr std::array<std::string_view, 3> kStreamParams = {"color", "tolerance_ms", "reference"};
StreamSettings parse_stream_params(const SourceUri& uri, StreamSettings defaults = {});

struct UsbUri {
  std::uint16_t vid = 0x10f8, pid = 0xc487;  // CESYS NanoUSB2
  std::optional<std::string> serial;
  int interface = 0;
  std::uint8_t endpoint = 0x86;  // bulk IN (unconfirmed in the spec: configurable)
  StreamSettings stream;
};
UsbUri parse_usb_uri(const SourceUri& uri);

enum class V4l2Layout { side_by_side, top_bottom, alternate };
enum class V4l2Format { y10, y16, grey, sgrbg10 };
const char* to_string(V4l2Layout l);
const char* to_string(V4l2Format f);
struct V4l2Uri {
  std::string device = "/dev/video0";
  V4l2Layout layout = V4l2Layout::side_by_side;
  std::optional<V4l2Format> format;  // unset: take what the device offers
  StreamSettings stream;
};
V4l2Uri parse_v4l2_uri(const SourceUri& uri);

struct FileUri {
  enum class Speed { realtime, max, factor };
  std::string path;
  Speed speed = Speed::realtime;
  double factor = 1.0;  // Speed::factor: recorded time / factor (2 = twice as fast)
  bool loop = false;
  std::size_t chunk_bytes = 16384;  // .raw files are fed in pieces of this size, like transfers
  StreamSettings stream;
};
FileUri parse_file_uri(const SourceUri& uri);

}  // namespace naneye::driver
