#pragma once
// Image files (PNG, JPEG, PGM/PPM, BMP, TIFF: whatever OpenCV's imdecode reads) to the 10-bit
// values the rest of the project works in. The one reader behind images:// and `naneye recon
// --left/--right`, and a fuzz target. Any size; the caller decides whether the size fits.
//
// Values: 8-bit files are scaled 0..255 -> 0..1023, 16-bit files 0..65535 -> 0..1023 (what most
// software writes when it saves a 10-bit sensor's frame), or kept as they are with bits=10 (a
// 16-bit container holding the sensor's own 10-bit values; a value above 1023 is then refused).
// Colour files are converted to grey (ITU-R 601 luma) for mono; a raw GRBG mosaic must be a
// single-channel file.
//
// Decoding allocates (OpenCV's cv::Mat, once per image): image input is not a hot path of a camera.
// `out` keeps its buffer, so the conversion itself reallocates only when the size grows.
#include <cstdint>
#include <filesystem>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "naneye/driver/frame.hpp"

namespace naneye::driver {

// Bytes that are not an image, or an image this project cannot use; what() says which and why.
class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ImageSettings {
  ColorMode color = ColorMode::mono;  // bayer_grbg: the file holds the raw mosaic (one channel)
  int bits16 = 16;                    // 16: 16-bit values are full scale; 10: they are 10-bit already
};

struct Image10 {
  int width = 0, height = 0;
  ColorMode color = ColorMode::mono;
  std::vector<std::uint16_t> pixels;  // row-major, width * height, 0..1023
};

// Largest image accepted: 4096 x 4096 pixels, far beyond any camera this project reads, so that a
// file claiming a huge canvas is refused (OpenCV itself decodes up to 2^30 pixels before we can see
// the size: set OPENCV_IO_MAX_IMAGE_PIXELS in the environment to bound that too).
inline constexpr long long kMaxImagePixels = 4096LL * 4096;

// Decodes `bytes`; throws ImageError naming `origin` (a path, or "<memory>") and the problem.
void decode_image(std::span<const std::uint8_t> bytes, const ImageSettings& options, Image10& out,
                  const std::string& origin = "<memory>");
// Reads the whole file and decodes it (files above 256 MiB are refused unread).
void read_image(const std::filesystem::path& file, const ImageSettings& options, Image10& out);

// True for the file name extensions read_image is meant for (.png .jpg .jpeg .pgm .ppm .pnm .bmp .tif
// .tiff, any case): how images://DIR picks its files.
bool is_image_file_name(const std::filesystem::path& file);

}  // namespace naneye::driver
