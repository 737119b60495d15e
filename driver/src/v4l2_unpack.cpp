#include "v4l2_unpack.hpp"

#include <linux/videodev2.h>

namespace naneye::driver {

std::uint32_t fourcc(V4l2Format f) {
  switch (f) {
    case V4l2Format::y10:
      return V4L2_PIX_FMT_Y10;
    case V4l2Format::y16:
      return V4L2_PIX_FMT_Y16;
    case V4l2Format::grey:
      return V4L2_PIX_FMT_GREY;
    case V4l2Format::sgrbg10:
      return V4L2_PIX_FMT_SGRBG10;
  }
  return 0;
}

int bytes_per_pixel(V4l2Format f) {
  return f == V4l2Format::grey ? 1 : 2;
}

void layout_size(V4l2Layout l, int& width, int& height) {
  width = l == V4l2Layout::side_by_side ? 2 * kSensorSize : kSensorSize;
  height = l == V4l2Layout::top_bottom ? 2 * kSensorSize : kSensorSize;
}

namespace v4l2_detail {

void eye_origin(V4l2Layout layout, int eye, int& x0, int& y0) {
  x0 = layout == V4l2Layout::side_by_side ? eye * kSensorSize : 0;
  y0 = layout == V4l2Layout::top_bottom ? eye * kSensorSize : 0;
}

void unpack_eye(const std::uint8_t* image, std::size_t stride, V4l2Format format, int x0, int y0,
                Frame& out) {
  const int bpp = bytes_per_pixel(format);
  std::uint16_t* dst = out.pixels.data();
  for (int r = 0; r < kSensorSize; ++r) {
    const std::uint8_t* src = image + static_cast<std::size_t>(y0 + r) * stride +
                              static_cast<std::size_t>(x0) * static_cast<std::size_t>(bpp);
    switch (format) {
      case V4l2Format::grey:
        // 8 -> 10 bits by bit replication, so that 255 maps to 1023 (full scale stays full scale).
        for (int c = 0; c < kSensorSize; ++c) dst[c] = static_cast<std::uint16_t>(src[c] << 2 | src[c] >> 6);
        break;
      case V4l2Format::y16:
        for (int c = 0; c < kSensorSize; ++c)
          dst[c] = static_cast<std::uint16_t>((src[2 * c] | src[2 * c + 1] << 8) >> 6);
        break;
      case V4l2Format::y10:
      case V4l2Format::sgrbg10:
        for (int c = 0; c < kSensorSize; ++c)
          dst[c] = static_cast<std::uint16_t>((src[2 * c] | src[2 * c + 1] << 8) & kPixelMax);
        break;
    }
    dst += kSensorSize;
  }
}

}  // namespace v4l2_detail
}  // namespace naneye::driver
