#pragma once
// A photograph as the corner detector and the scene paths read a frame: 8-bit grey to 10-bit DN
// (x 4, the scale their physical constants are stated in), every pixel image (no NanEye padding
// column or reference rows). For the tests on photographs nobody here made (opencv-doc).
#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

#include "naneye/recon/corners/detector.hpp"

namespace naneye::test {

struct PhotoFrame {
  std::vector<std::uint16_t> dn;
  int width = 0, height = 0;
  recon::RawImageView view() const {
    return {dn.data(), width, height, width, recon::PixelLayout::mono, 0, 0};
  }
};

inline PhotoFrame photo_frame(const cv::Mat& gray) {
  PhotoFrame f{std::vector<std::uint16_t>(gray.total()), gray.cols, gray.rows};
  for (int r = 0; r < gray.rows; ++r)
    for (int c = 0; c < gray.cols; ++c)
      f.dn[static_cast<std::size_t>(r) * gray.cols + c] =
          static_cast<std::uint16_t>(4 * gray.at<std::uint8_t>(r, c));
  return f;
}

}  // namespace naneye::test
