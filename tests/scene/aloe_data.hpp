#pragma once
// Middlebury's Aloe (Scharstein & Pal, CVPR 2007) as Debian's opencv-doc ships it, already
// rectified: the scene tests' real stereo pair with ground truth. aloeGT.png is the left view's
// disparity at the images' full size (1282 x 1110), in pixels, 0 = unknown (ximgproc's readGT reads
// it so).
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>

namespace naneye::test {

inline const std::filesystem::path kAloeDir = "/usr/share/doc/opencv-doc/examples/data";
constexpr int kAloeDown = 4;  // a quarter of the size (320 x 277; keeps the tests short)

struct AloeQuarter {
  cv::Mat l, r;  // 8-bit grey views
  cv::Mat gt;    // CV_32FC1, the left view's disparity in quarter-size pixels, 0 = unknown
};

// Empty views when opencv-doc is not installed.
inline AloeQuarter load_aloe_quarter() {
  AloeQuarter a;
  const cv::Mat L = cv::imread((kAloeDir / "aloeL.jpg").string(), cv::IMREAD_GRAYSCALE);
  const cv::Mat R = cv::imread((kAloeDir / "aloeR.jpg").string(), cv::IMREAD_GRAYSCALE);
  const cv::Mat G = cv::imread((kAloeDir / "aloeGT.png").string(), cv::IMREAD_GRAYSCALE);
  if (L.empty() || R.empty() || G.empty()) return a;
  cv::resize(L, a.l, cv::Size(), 1.0 / kAloeDown, 1.0 / kAloeDown, cv::INTER_AREA);
  cv::resize(R, a.r, cv::Size(), 1.0 / kAloeDown, 1.0 / kAloeDown, cv::INTER_AREA);
  a.gt.create(a.l.rows, a.l.cols, CV_32FC1);
  for (int y = 0; y < a.gt.rows; ++y)
    for (int x = 0; x < a.gt.cols; ++x) {
      // The block's centre pixel (unknown stays unknown; no averaging across depth edges).
      const int gy = std::min(G.rows - 1, y * kAloeDown + kAloeDown / 2),
                gx = std::min(G.cols - 1, x * kAloeDown + kAloeDown / 2);
      const int v = G.at<std::uint8_t>(gy, gx);
      a.gt.at<float>(y, x) = v > 0 ? static_cast<float>(v) / kAloeDown : 0.f;
    }
  return a;
}

}  // namespace naneye::test
