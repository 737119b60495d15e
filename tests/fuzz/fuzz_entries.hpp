#pragma once
// The fuzzed entry points, shared by the libFuzzer targets (clang, -DNANEYE_FUZZ=ON; one per entry,
// tests/fuzz/fuzz_target.cpp) and by the corpus replay test that every build runs. Each aborts on a
// broken invariant; an exception other than the parser's documented error escapes (a crash).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

namespace naneye::fuzz {

// An invariant of a parser's output: a broken one aborts, which libFuzzer reports as a crash.
inline void fuzz_check(bool ok) {
  if (!ok) std::abort();
}

using Entry = int (*)(const std::uint8_t* data, std::size_t size);

// data[0]: chunking, data[1]: sensor size and parser options, the rest: the byte stream.
int parse_stream(const std::uint8_t* data, std::size_t size);
// data: a whole .neyd file; its chunks go through the parser (4 x 4 sensor records).
int read_neyd(const std::uint8_t* data, std::size_t size);
// data: a calibration file (the YAML OpenCV's FileStorage writes), read by recon::parse_rig (libyaml).
int load_calibration(const std::uint8_t* data, std::size_t size);
// data: naneyed's TOML configuration (daemon::parse_settings).
int parse_daemon_toml(const std::uint8_t* data, std::size_t size);
// data: a USB device profile (config/devices/*.toml).
int parse_device_profile(const std::uint8_t* data, std::size_t size);
// data: a source URI, through parse_uri and every scheme's parser.
int parse_source_uri(const std::uint8_t* data, std::size_t size);
// data: a query string, through httplib's splitting and the daemon's strict parameter checks.
int parse_http_query(const std::uint8_t* data, std::size_t size);
// data[0..3]: format, layout, bytesperline, bytesused; the rest: a V4L2 buffer's pixels.
int unpack_v4l2(const std::uint8_t* data, std::size_t size);
// data[0]: reader options; the rest: an image file (driver::decode_image).
int decode_image_file(const std::uint8_t* data, std::size_t size);

struct NamedEntry {
  std::string_view name;  // the corpus folder tests/fuzz/corpus/<name> and the target fuzz_<name>
  Entry entry;
};
inline constexpr NamedEntry kEntries[] = {
    {"parser", parse_stream},
    {"neyd", read_neyd},
    {"calib_yaml", load_calibration},
    {"daemon_toml", parse_daemon_toml},
    {"device_profile", parse_device_profile},
    {"source_uri", parse_source_uri},
    {"http_query", parse_http_query},
    {"v4l2_unpack", unpack_v4l2},
    {"image", decode_image_file},
};

}  // namespace naneye::fuzz
