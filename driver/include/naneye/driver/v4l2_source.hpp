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

#include "naneye/base/backoff.hpp"
#include "naneye/driver/frame_source.hpp"
#include "naneye/driver/source_uri.hpp"
#include "naneye/driver/stream_parser.hpp"

namespace naneye::driver {

// V4l2Layout and V4l2Format (and their to_string) come with the URI parser (source_uri.hpp):
//   side-by-side 500 x 250 left | right; top-bottom 250 x 500 left above right; alternate 250 x 250,
//   one eye per buffer (field TOP = left, BOTTOM = right, else sequence parity: even = left).
//   Y10 and SGRBG10: 10 bits in u16 LE; Y16: 16 bits, top 10 kept; GREY: 8 bits, scaled to 10.
std::uint32_t fourcc(V4l2Format f);
int bytes_per_pixel(V4l2Format f);
// Image size the layout needs (both eyes for side-by-side/top-bottom, one for alternate).
void layout_size(V4l2Layout l, int& width, int& height);

struct V4l2Settings {
  std::string device = "/dev/video0";
  V4l2Layout layout = V4l2Layout::side_by_side;
  std::optional<V4l2Format> format;   // unset: the first of Y10, Y16, SGRBG10, GREY the device offers
  ColorMode color = ColorMode::mono;  // for the grey formats (SGRBG10 is always Bayer GRBG)
  int buffer_count = 4;
  std::chrono::milliseconds poll_timeout{200};
  std::chrono::milliseconds stall_timeout{1000};
  base::BackoffSettings backoff;  // reopen delays (base/backoff.hpp's defaults)
  // alternate layout: a left and a right frame pair when their timestamps differ by at most this
  // (default: half of a 22.7 ms frame period).
  std::chrono::nanoseconds pair_tolerance{11'350'000};
  std::size_t pool_size = 8;
  std::size_t ring_size = 4;
  // Off unless asked for: whether a grabber passes the sensor's reference pixels through (rather
  // than cropping or processing them) is not known in general (docs/drivers.md).
  ReferenceCheck reference{.enabled = false};
};

// The URI's device, layout, format, colour and pairing tolerance.
V4l2Settings v4l2_settings_from(const V4l2Uri& uri);

// Throws SourceError when the node exists but cannot give the layout/format (named in the message).
// A node that is absent at start() is waited for (state waiting_for_device).
std::unique_ptr<FrameSource> make_v4l2_source(V4l2Settings settings, std::string uri = {});

}  // namespace naneye::driver
