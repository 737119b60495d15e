#include "v4l2_unpack.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <cctype>

namespace naneye::driver {

const char* to_string(V4l2Layout l) {
  switch (l) {
    case V4l2Layout::side_by_side:
      return "side-by-side";
    case V4l2Layout::top_bottom:
      return "top-bottom";
    case V4l2Layout::alternate:
      return "alternate";
  }
  return "?";
}

const char* to_string(V4l2Format f) {
  switch (f) {
    case V4l2Format::y10:
      return "Y10";
    case V4l2Format::y16:
      return "Y16";
    case V4l2Format::grey:
      return "GREY";
    case V4l2Format::sgrbg10:
      return "SGRBG10";
  }
  return "?";
}

std::optional<V4l2Layout> parse_v4l2_layout(const std::string& s) {
  for (auto l : {V4l2Layout::side_by_side, V4l2Layout::top_bottom, V4l2Layout::alternate})
    if (s == to_string(l)) return l;
  return std::nullopt;
}

std::optional<V4l2Format> parse_v4l2_format(const std::string& s) {
  std::string up = s;
  std::transform(up.begin(), up.end(), up.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  for (auto f : {V4l2Format::y10, V4l2Format::y16, V4l2Format::grey, V4l2Format::sgrbg10})
    if (up == to_string(f)) return f;
  return std::nullopt;
}

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
  out.color = format == V4l2Format::sgrbg10 ? ColorMode::bayer_grbg : ColorMode::mono;
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
