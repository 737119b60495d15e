// The fuzzed pixel inputs: V4L2 buffers as a device hands them over, and image files.
#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "fuzz_entries.hpp"
#include "naneye/driver/image_file.hpp"
#include "naneye/driver/v4l2_source.hpp"
#include "v4l2_unpack.hpp"

namespace naneye::fuzz {
namespace {

using namespace naneye::driver;

// Largest buffer a configuration below can describe: side by side (500 px), 2 bytes a pixel, a
// bytesperline up to 255 bytes beyond the minimum, 250 rows; top-bottom is 250 px by 500 rows.
constexpr std::size_t kMaxBuffer = (2 * kSensorSize * 2 + 255) * 2 * kSensorSize;
// The buffer sits at the end of a global (ASan puts a redzone after it): reading past the image
// the driver was told about is reading past the array.
alignas(64) std::uint8_t g_buffer[kMaxBuffer];

// Every bit set in any pixel: all pixels are <= kPixelMax iff this is (kPixelMax is 2^n - 1).
// Outside libFuzzer's comparison tracing (tests/fuzz/coverage_ignore.txt): per pixel it is no
// input's decision.
static_assert((kPixelMax & (kPixelMax + 1)) == 0);
template <typename Pixels>
std::uint16_t all_pixel_bits(const Pixels& pixels) {
  std::uint16_t bits = 0;
  for (const std::uint16_t v : pixels) bits |= v;
  return bits;
}

}  // namespace

int unpack_v4l2(const std::uint8_t* data, std::size_t size) {
  // data[0]: format (2 bits), layout (2 bits), eye; data[1]: bytesperline beyond the minimum;
  // data[2..3]: bytesused short of the image (0: whole); the rest: the pixels.
  if (size < 4) return 0;
  static constexpr V4l2Format kFormats[] = {V4l2Format::y10, V4l2Format::y16, V4l2Format::grey,
                                            V4l2Format::sgrbg10};
  static constexpr V4l2Layout kLayouts[] = {V4l2Layout::side_by_side, V4l2Layout::top_bottom,
                                            V4l2Layout::alternate, V4l2Layout::side_by_side};
  const V4l2Format format = kFormats[data[0] & 3];
  const V4l2Layout layout = kLayouts[(data[0] >> 2) & 3];
  const int eye = (data[0] >> 4) & 1;
  int width = 0, height = 0;
  layout_size(layout, width, height);
  // As v4l2_device.cpp negotiates them: the minimum bytesperline or more, image = stride x height.
  const std::size_t stride = static_cast<std::size_t>(width) * bytes_per_pixel(format) + data[1];
  const std::size_t image = stride * static_cast<std::size_t>(height);
  const std::size_t bytesused = image - std::min<std::size_t>(image, data[2] | data[3] << 8);
  fuzz_check(image <= kMaxBuffer);
  std::uint8_t* img = g_buffer + kMaxBuffer - image;
  std::memcpy(img, data + 4, std::min(size - 4, image));
  // v4l2_source.cpp's guard: a buffer shorter than the image is counted as cut, never unpacked.
  if (bytesused < image) return 0;
  static Frame frame;  // 125 kB: kept across inputs
  int x0 = 0, y0 = 0;
  v4l2_detail::eye_origin(layout, layout == V4l2Layout::alternate ? 0 : eye, x0, y0);
  v4l2_detail::unpack_eye(img, stride, format, x0, y0, frame);
  fuzz_check(all_pixel_bits(frame.pixels) <= kPixelMax);
  return 0;
}

int decode_image_file(const std::uint8_t* data, std::size_t size) {
  // data[0]: options (mosaic, bits=10); the rest: the file.
  if (size < 1) return 0;
  ImageSettings o;
  o.color = (data[0] & 1) ? ColorMode::bayer_grbg : ColorMode::mono;
  o.bits16 = (data[0] & 2) ? 10 : 16;
  static Image10 image;  // its buffer is reused, as images:// does
  try {
    decode_image(std::span<const std::uint8_t>(data + 1, size - 1), o, image);
    fuzz_check(image.width > 0 && image.height > 0 &&
               image.pixels.size() == static_cast<std::size_t>(image.width) * image.height);
    fuzz_check(static_cast<long long>(image.width) * image.height <= kMaxImagePixels);
    fuzz_check(all_pixel_bits(image.pixels) <= kPixelMax);
  } catch (const ImageError& e) {
    fuzz_check(std::string(e.what()).starts_with("<memory>: "));
  }
  return 0;
}

}  // namespace naneye::fuzz
