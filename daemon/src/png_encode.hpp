#pragma once
// PNG encoding through libpng. cv::imencode would do, but OpenCV's imgcodecs drags GDAL, GDCM,
// poppler and ~100 more shared libraries into the process (~40 MB resident on Debian 12), and
// naneyed aims at a small steady RSS.
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <vector>

namespace naneye::daemon::http {

// 8-bit gray (CV_8UC1), BGR (CV_8UC3) or 16-bit gray (CV_16UC1) -> PNG bytes; false on a libpng error.
bool encode_png(const cv::Mat& img, std::vector<std::uint8_t>& out);

}  // namespace naneye::daemon::http
