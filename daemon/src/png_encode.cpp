#include "png_encode.hpp"

#include <png.h>

#include <csetjmp>

namespace naneye::daemon::http {
namespace {

void append(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + n);
}

}  // namespace

bool encode_png(const cv::Mat& img, std::vector<std::uint8_t>& out) {
  const bool wide = img.type() == CV_16UC1;
  if (!wide && (img.depth() != CV_8U || (img.channels() != 1 && img.channels() != 3))) return false;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  out.clear();
  // libpng reports errors by longjmp; nothing with a destructor lives between here and the end.
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &out, append, nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(img.cols), static_cast<png_uint_32>(img.rows),
               wide ? 16 : 8, img.channels() == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 3);
  png_write_info(png, info);
  if (img.channels() == 3) png_set_bgr(png);  // OpenCV's order
  // PNG stores 16-bit samples big-endian; this host's are little-endian.
  if (wide && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__) png_set_swap(png);
  for (int r = 0; r < img.rows; ++r) png_write_row(png, img.ptr<png_byte>(r));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace naneye::daemon::http
