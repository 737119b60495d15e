// /v1/frames/left.png and right.png: the latest frames, 10-bit -> 8-bit, optionally with the
// detected corners drawn; /v1/domain/left.png and right.png: where each camera's model is valid.
#include <opencv2/imgproc.hpp>

#include "http_internal.hpp"
#include "png_encode.hpp"

namespace naneye::daemon::http {
namespace {

void frame_route(httplib::Server& svr, HttpContext& ctx, const char* path, bool left) {
  svr.Get(path, [&ctx, left](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {"overlay"})) return;
    std::optional<std::int64_t> overlay;
    if (!int_param(req, res, "overlay", 0, 1, overlay)) return;
    cv::Mat img;
    std::uint64_t pair = 0;
    std::vector<cv::Point2d> corners;
    bool bayer = false;
    const bool have = ctx.pipeline->frames().read_latest([&](const FrameSnapshot& f, std::uint64_t) {
      const auto& px = left ? f.left : f.right;
      img.create(driver::kSensorSize, driver::kSensorSize, CV_8UC1);
      // 10-bit samples to 8 bits: drop the two least significant bits.
      for (std::size_t i = 0; i < px.size(); ++i)
        img.data[i] = static_cast<std::uint8_t>(std::min<int>(px[i], 1023) >> 2);
      pair = f.pair;
      bayer = f.color == driver::ColorMode::bayer_grbg;
      for (int i = 0; i < f.corners; ++i) {
        const auto& c =
            left ? f.left_px[static_cast<std::size_t>(i)] : f.right_px[static_cast<std::size_t>(i)];
        corners.emplace_back(c.x(), c.y());
      }
    });
    if (!have) return send_error(res, 503, "no_frame", "no frame has been received yet");
    // A GRBG sensor (G R on the first row) is OpenCV's "BayerGB" (named after the second row).
    if (bayer) cv::cvtColor(img, img, cv::COLOR_BayerGB2BGR);
    if (overlay.value_or(0) == 1) {
      if (!bayer) cv::cvtColor(img, img, cv::COLOR_GRAY2BGR);
      constexpr int kShift = 4;  // sub-pixel drawing: coordinates in 1/16 px
      for (std::size_t i = 0; i < corners.size(); ++i) {
        const cv::Point c(cvRound(corners[i].x * (1 << kShift)), cvRound(corners[i].y * (1 << kShift)));
        const cv::Scalar colour = i == 0 ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 255, 0);
        cv::circle(img, c, 3 << kShift, colour, 1, cv::LINE_AA, kShift);
      }
    }
    std::vector<std::uint8_t> png;
    if (!encode_png(img, png)) return send_error(res, 500, "encode_failed", "PNG encoding failed");
    res.set_header("X-Naneye-Pair", std::to_string(pair));
    res.set_content(std::string(png.begin(), png.end()), "image/png");
  });
}

// The camera's valid domain as an 8-bit mask on its raw grid: 255 where the pixel centre undistorts
// (CameraModel::undistort succeeds), 0 beyond the fold, where nothing is measured. Computed per
// request (62 500 Newton solves, a few ms): it is asked for once per calibration, not per frame.
void domain_route(httplib::Server& svr, HttpContext& ctx, const char* path, bool left) {
  svr.Get(path, [&ctx, left](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    const auto rig = ctx.pipeline->rig();
    const auto& cam = left ? rig->left : rig->right;
    cv::Mat mask(cam.height(), cam.width(), CV_8UC1);
    for (int v = 0; v < mask.rows; ++v)
      for (int u = 0; u < mask.cols; ++u)
        mask.at<std::uint8_t>(v, u) = cam.in_domain(Eigen::Vector2d(u, v)) ? 255 : 0;
    std::vector<std::uint8_t> png;
    if (!encode_png(mask, png)) return send_error(res, 500, "encode_failed", "PNG encoding failed");
    res.set_content(std::string(png.begin(), png.end()), "image/png");
  });
}

}  // namespace

void add_frame_routes(httplib::Server& svr, HttpContext& ctx) {
  frame_route(svr, ctx, "/v1/frames/left.png", true);
  frame_route(svr, ctx, "/v1/frames/right.png", false);
  domain_route(svr, ctx, "/v1/domain/left.png", true);
  domain_route(svr, ctx, "/v1/domain/right.png", false);
}

}  // namespace naneye::daemon::http
