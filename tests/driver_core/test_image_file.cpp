// driver::read_image: image files of any size to 10-bit values, and a clear error for every file it
// cannot use (images:// and `naneye recon --left/--right` share it).
#include <gtest/gtest.h>

#include "image_test_files.hpp"
#include "naneye/driver/image_file.hpp"

namespace naneye::driver {
namespace {

std::string image_error_of(const std::string& path, ImageSettings o = {}) {
  Image10 im;
  try {
    read_image(path, o, im);
  } catch (const ImageError& e) {
    return e.what();
  }
  return "";
}

TEST(ImageFile, ReadsOpenCvsStereoPhotographsAtTheirOwnSize) {
  const std::string path = test::opencv_photo("left01.jpg");
  ASSERT_TRUE(std::filesystem::exists(path)) << path << ": install opencv-doc (scripts/install-deps.sh)";
  Image10 im;
  read_image(path, {}, im);
  EXPECT_EQ(im.width, 640);
  EXPECT_EQ(im.height, 480);
  ASSERT_EQ(im.pixels.size(), 640u * 480u);
  // The same decoder's 8-bit values, scaled 255 -> 1023 with rounding.
  const cv::Mat ref = cv::imread(path, cv::IMREAD_GRAYSCALE);
  for (const auto& [r, c] : {std::pair{0, 0}, {240, 320}, {479, 639}, {100, 500}}) {
    const unsigned v = ref.at<std::uint8_t>(r, c);
    EXPECT_EQ(im.pixels[static_cast<std::size_t>(r) * 640 + c], (v * 1023 + 127) / 255) << r << "," << c;
  }
  // A colour photograph (left.jpg, 612 x 459, 3 channels) becomes one grey channel.
  read_image(test::opencv_photo("left.jpg"), {}, im);
  EXPECT_EQ(im.width, 612);
  EXPECT_EQ(im.height, 459);
  EXPECT_EQ(im.pixels.size(), 612u * 459u);
}

TEST(ImageFile, EightAndSixteenBitFilesBecomeTenBitValues) {
  test::TempDir dir("image-depth");
  cv::Mat g8 = (cv::Mat_<std::uint8_t>(1, 4) << 0, 128, 255, 1);
  cv::Mat g16 = (cv::Mat_<std::uint16_t>(1, 4) << 0, 32768, 65535, 1000);
  Image10 im;
  read_image(dir.image("g8.png", g8), {}, im);
  EXPECT_EQ(im.pixels, (std::vector<std::uint16_t>{0, 514, 1023, 4}));
  read_image(dir.image("g16.png", g16), {}, im);
  EXPECT_EQ(im.pixels, (std::vector<std::uint16_t>{0, 512, 1023, 16}));
  read_image(dir.image("g16.pgm", g16), {}, im);  // PGM too (a 16-bit P5)
  EXPECT_EQ(im.pixels, (std::vector<std::uint16_t>{0, 512, 1023, 16}));
  // bits=10: a 16-bit container holding the sensor's own values is kept as is ...
  ImageSettings ten;
  ten.bits16 = 10;
  cv::Mat raw10 = (cv::Mat_<std::uint16_t>(1, 3) << 0, 513, 1023);
  read_image(dir.image("raw10.png", raw10), ten, im);
  EXPECT_EQ(im.pixels, (std::vector<std::uint16_t>{0, 513, 1023}));
  // ... and a value it cannot hold is refused, not clipped.
  EXPECT_NE(image_error_of(dir.image("g16b.png", g16), ten).find("above 1023"), std::string::npos);
}

TEST(ImageFile, FilesItCannotUseGiveAnErrorNamingTheFileAndWhy) {
  test::TempDir dir("image-broken");
  const cv::Mat frame = test::ramp(0, 16);
  std::vector<std::uint8_t> png;
  cv::imencode(".png", frame, png);
  const std::string cut = dir.bytes("cut.png", std::string(png.begin(), png.begin() + 40));
  const std::string text = dir.bytes("notes.png", "this is not an image\n");
  const std::string empty = dir.bytes("empty.jpg", "");
  for (const auto& [path, why] : {std::pair{cut, "not a readable image"},
                                  {text, "not a readable image"},
                                  {empty, "empty file"},
                                  {dir.file("missing.png"), "cannot read"},
                                  {dir.str(), "cannot read"}}) {
    const std::string e = image_error_of(path);
    EXPECT_EQ(e.rfind(path + ": ", 0), 0u) << e;
    EXPECT_NE(e.find(why), std::string::npos) << e;
  }
  // A mosaic must be one channel: a colour file cannot be a raw GRBG frame.
  ImageSettings grbg;
  grbg.color = ColorMode::bayer_grbg;
  const cv::Mat colour(4, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  EXPECT_NE(image_error_of(dir.image("colour.png", colour), grbg).find("one channel"), std::string::npos);
  // Floating-point images (TIFF can hold them) are not frames.
  const cv::Mat f32(4, 4, CV_32F, cv::Scalar(0.5));
  EXPECT_NE(image_error_of(dir.image("float.tif", f32)).find("8- or 16-bit"), std::string::npos);
}

}  // namespace
}  // namespace naneye::driver
