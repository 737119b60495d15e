#pragma once
// Image files written by the tests (OpenCV's encoders), in a folder removed when the test ends.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

namespace naneye::driver::test {

// OpenCV's own stereo chessboard photographs (Debian's opencv-doc, scripts/install-deps.sh):
// 640 x 480, 8-bit grey JPEG, left01..left14 without 10.
inline std::string opencv_photo(const std::string& name) {
  return "/usr/share/doc/opencv-doc/examples/data/" + name;
}

class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("naneye-" + std::to_string(::getpid()) + "-" + name)) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string str() const { return path_.string(); }
  // Writes `m` with the encoder the extension names; returns the path.
  std::string image(const std::string& name, const cv::Mat& m) const {
    const std::string p = file(name);
    cv::imwrite(p, m);
    return p;
  }
  std::string bytes(const std::string& name, const std::string& content) const {
    const std::string p = file(name);
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }

 private:
  std::filesystem::path path_;
};

// A 250 x 250 8-bit frame whose pixel (r, c) is (r + c + seed) mod 256: every pair distinguishable.
inline cv::Mat ramp(int seed, int size = 250) {
  cv::Mat m(size, size, CV_8U);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) m.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>((r + c + seed) % 256);
  return m;
}

}  // namespace naneye::driver::test
