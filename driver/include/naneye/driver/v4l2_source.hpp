#pragma once
// v4l2://: a capture device (e.g. a frame grabber or a UVC bridge in front of the camera) whose frames
// are already images, so no record parser is involved: each dequeued buffer is unpacked straight into
// a pooled StereoPair. Streaming I/O through glibc open/ioctl/mmap (not libv4l2, whose raw syscalls
// cannot be emulated in tests and whose format conversions would hide the sensor's 10 bits).
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "naneye/driver/frame_source.hpp"

namespace naneye::driver {

enum class V4l2Layout {
  side_by_side,  // 500 x 250: left | right
  top_bottom,    // 250 x 500: left above right
  alternate,     // 250 x 250: frames alternate left, right (by field TOP/BOTTOM, else sequence parity)
};
enum class V4l2Format {
  y10,      // V4L2_PIX_FMT_Y10: 10 bits in u16 LE
  y16,      // V4L2_PIX_FMT_Y16: 16 bits, top 10 kept
  grey,     // V4L2_PIX_FMT_GREY: 8 bits, scaled to 10
  sgrbg10,  // V4L2_PIX_FMT_SGRBG10: GRBG Bayer, 10 bits in u16 LE
};

const char* to_string(V4l2Layout l);
const char* to_string(V4l2Format f);
std::optional<V4l2Layout> parse_v4l2_layout(
    const std::string& s);  // "side-by-side", "top-bottom", "alternate"
std::optional<V4l2Format> parse_v4l2_format(const std::string& s);  // "Y10", "Y16", "GREY", "SGRBG10"
std::uint32_t fourcc(V4l2Format f);
int bytes_per_pixel(V4l2Format f);
// Image size the layout needs (both eyes for side-by-side/top-bottom, one for alternate).
void layout_size(V4l2Layout l, int& width, int& height);

struct V4l2Settings {
  std::string device = "/dev/video0";
  V4l2Layout layout = V4l2Layout::side_by_side;
  V4l2Format format = V4l2Format::y10;
  int buffer_count = 4;
  std::chrono::milliseconds poll_timeout{200};
  std::chrono::milliseconds stall_timeout{1000};
  std::chrono::milliseconds backoff_initial{100};
  std::chrono::milliseconds backoff_max{5000};
  // alternate layout: a left and a right frame pair when their timestamps differ by at most this
  // (default: half of a 22.7 ms frame period).
  std::chrono::microseconds pair_tolerance{11'350};
  std::size_t pool_size = 8;
  std::size_t ring_size = 4;
};

// Throws SourceError when the node exists but cannot give the layout/format (named in the message).
// A node that is absent at start() is waited for (state waiting_for_device).
std::unique_ptr<FrameSource> make_v4l2_source(V4l2Settings settings, std::string uri = {});

}  // namespace naneye::driver
