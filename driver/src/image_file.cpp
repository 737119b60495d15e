#include "naneye/driver/image_file.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>  // the IMREAD_ flags only: the library is loaded on first use
#include <opencv2/imgproc.hpp>

#include "imdecode_lazy.hpp"

namespace naneye::driver {
namespace {

// 256 MiB: a 4096 x 4096 16-bit TIFF uncompressed is 32 MiB; anything this big is not a frame.
constexpr std::uintmax_t kMaxFileBytes = 256ull << 20;

[[noreturn]] void fail(const std::string& origin, const std::string& what) {
  throw ImageError(origin + ": " + what);
}

// 0..max -> 0..1023, rounded to nearest (255 -> 1023 and 65535 -> 1023 exactly).
template <typename T>
void scale_into(const cv::Mat& m, std::uint32_t max, std::uint16_t* out) {
  for (int r = 0; r < m.rows; ++r) {
    const T* row = m.ptr<T>(r);
    for (int c = 0; c < m.cols; ++c)
      *out++ = static_cast<std::uint16_t>((std::uint32_t{row[c]} * kPixelMax + max / 2) / max);
  }
}

// The formats this reader is for, by their first bytes: PNG, JPEG, PBM/PGM/PPM (P1..P6), BMP, TIFF.
// Everything else is refused before OpenCV picks a decoder: imdecode would also hand the bytes to
// GDCM (DICOM), OpenJPEG, OpenEXR..., and fuzz_image found files on which libgdcm's own assert()
// aborts the process or it allocates 4 GB. Each test is exactly OpenCV's own for that format (a
// netpbm header needs its whitespace), so that no accepted file falls through to another decoder.
bool known_signature(std::span<const std::uint8_t> b) {
  const auto starts = [&](std::initializer_list<std::uint8_t> sig) {
    return b.size() >= sig.size() && std::equal(sig.begin(), sig.end(), b.begin());
  };
  return starts({0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}) || starts({0xff, 0xd8, 0xff}) ||
         (b.size() >= 3 && b[0] == 'P' && b[1] >= '1' && b[1] <= '6' && std::isspace(b[2])) ||
         starts({'B', 'M'}) || starts({'I', 'I', 0x2a, 0x00}) || starts({'M', 'M', 0x00, 0x2a});
}

}  // namespace

bool is_image_file_name(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".pgm", ".ppm", ".pnm", ".bmp", ".tif", ".tiff"})
    if (ext == e) return true;
  return false;
}

void decode_image(std::span<const std::uint8_t> bytes, const ImageSettings& options, Image10& out,
                  const std::string& origin) {
  if (bytes.empty()) fail(origin, "empty file, not an image");
  if (!known_signature(bytes))
    fail(origin, "not a readable image (PNG, JPEG, PGM/PPM, BMP or TIFF expected; its first bytes are none)");
  cv::Mat m;
  try {
    // The file's own depth and channels: the 10-bit scaling and the mosaic check need them.
    const cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8U, const_cast<std::uint8_t*>(bytes.data()));
    m = imdecode_lazy(raw, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception& e) {
    fail(origin, std::string("not a readable image (OpenCV: ") + e.err + ")");
  }
  if (m.empty()) fail(origin, "not a readable image (PNG, JPEG, PGM/PPM, BMP or TIFF expected)");
  if (static_cast<long long>(m.cols) * m.rows > kMaxImagePixels)
    fail(origin, std::to_string(m.cols) + " x " + std::to_string(m.rows) + " pixels is larger than " +
                     std::to_string(kMaxImagePixels) + " (4096 x 4096)");
  if (m.depth() != CV_8U && m.depth() != CV_16U)
    fail(origin, "pixel type not 8- or 16-bit unsigned (floating-point and signed images are not frames)");
  if (m.channels() != 1) {
    if (options.color == ColorMode::bayer_grbg)
      fail(origin, std::to_string(m.channels()) +
                       " channels: a raw GRBG mosaic is one channel (save it as a grey image)");
    cv::Mat grey;
    cv::cvtColor(m, grey, m.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    m = grey;
  }
  out.width = m.cols;
  out.height = m.rows;
  out.color = options.color;
  out.pixels.resize(static_cast<std::size_t>(m.cols) * m.rows);
  if (m.depth() == CV_8U) {
    scale_into<std::uint8_t>(m, 255, out.pixels.data());
  } else if (options.bits16 == 10) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(m, &lo, &hi);
    if (hi > kPixelMax)
      fail(origin, "bits=10 but a value is " + std::to_string(static_cast<int>(hi)) + " (above 1023)");
    for (int r = 0; r < m.rows; ++r)
      std::copy_n(m.ptr<std::uint16_t>(r), m.cols, out.pixels.data() + static_cast<std::size_t>(r) * m.cols);
  } else {
    scale_into<std::uint16_t>(m, 65535, out.pixels.data());
  }
}

void read_image(const std::filesystem::path& file, const ImageSettings& options, Image10& out) {
  const std::string origin = file.string();
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) fail(origin, "cannot read: " + ec.message());
  if (size > kMaxFileBytes) fail(origin, std::to_string(size) + " bytes is too large for an image file");
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(origin, std::string("cannot open: ") + std::strerror(errno));
  std::vector<std::uint8_t> bytes(size);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) fail(origin, "cannot read the whole file");
  decode_image(bytes, options, out, origin);
}

}  // namespace naneye::driver
