// /v1/depth.png (the dense map as 16-bit PNG, Z in 0.01 mm on the left raw grid, 0 = no depth) and
// /v1/depth/colour.png (the same colour-mapped, with a scale bar in mm below it); with ?layer=, the
// map's match or calibration sigmas instead of its depths. Both of the latest result's own map: a
// map is never served for another pair than the one it was computed on.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "http_internal.hpp"
#include "naneye/app/depth_png.hpp"
#include "png_encode.hpp"

namespace naneye::daemon::http {
namespace {

constexpr int kBarHeight = 36;  // px below the map: the colour bar and its labels
// The colour scale spans these quantiles of the pair's depths: a few stray far or near pixels must
// not squeeze every other depth into one colour.
constexpr double kScaleLowQuantile = 0.01, kScaleHighQuantile = 0.99;

// Turbo (Google's polynomial approximation, Mikhailov 2019), as daemon/web/colormap.js draws it, so
// the page's own scales and this image agree. t in [0, 1] -> BGR.
cv::Vec3b turbo(double t) {
  const double x = std::clamp(t, 0.0, 1.0);
  const double r = 34.61 + x * (1172.33 - x * (10793.56 - x * (33300.12 - x * (38394.49 - x * 14825.05))));
  const double g = 23.31 + x * (557.33 + x * (1225.33 - x * (3574.96 - x * (1073.77 + x * 707.56))));
  const double b = 27.2 + x * (3211.1 - x * (15327.97 - x * (27814.0 - x * (22569.18 - x * 6838.66))));
  auto c = [](double v) { return static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0, 255.0))); };
  return {c(b), c(g), c(r)};
}

struct MapCopy {
  std::uint64_t pair = 0;
  int width = 0, height = 0;
  std::vector<float> values;  // mm, of the layer asked for (depth unless told otherwise)
  bool calib_sigma = false;   // the map carries calibration sigmas (its calibration had a covariance)
  int valid_count = 0;
};

// Copies one layer of the latest result's map out of its slot (the slot stays pinned only for the
// copy). False with the error sent when there is none.
bool latest_map(HttpContext& ctx, httplib::Response& res, MapCopy& out,
                app::DepthLayer layer = app::DepthLayer::depth) {
  bool has_dense = false, scene = false, held = false;
  const bool have = read_latest_with_map(*ctx.pipeline, [&](const Published& p, const DepthSlot* d) {
    out.pair = p.result.pair;
    scene = p.scene.computed;
    has_dense = p.scene.dense;
    if (!d) return;
    held = true;
    out.width = d->map.width;
    out.height = d->map.height;
    const auto& v = app::layer_values(d->map, layer);
    out.values.assign(v.begin(), v.end());
    out.calib_sigma = std::isfinite(d->map.calib_sigma_median_mm);
    out.valid_count = d->map.valid_count;
  });
  if (!have) {
    send_error(res, 503, "no_result", "no stereo pair has been reconstructed yet");
    return false;
  }
  if (!has_dense) {
    send_error(res, 503, "no_depth_map",
               scene ? "the latest pair has no dense depth map"
                     : "scene reconstruction is off ([recon] mode = \"board\"): there is no dense depth map");
    return false;
  }
  if (!held || out.values.size() != static_cast<std::size_t>(out.width) * out.height || out.width <= 0) {
    send_error(res, 503, "depth_map_gone", "the latest result's dense map was replaced; retry");
    return false;
  }
  return true;
}

void send_png(httplib::Response& res, const cv::Mat& img, std::uint64_t pair, const std::string& name) {
  std::vector<std::uint8_t> png;
  if (!encode_png(img, png)) return send_error(res, 500, "encode_failed", "PNG encoding failed");
  res.set_header("X-Naneye-Pair", std::to_string(pair));
  res.set_header("Content-Disposition",
                 "inline; filename=\"naneye-" + std::to_string(pair) + "-" + name + ".png\"");
  res.set_content(std::string(png.begin(), png.end()), "image/png");
}

std::string mm_label(double v) {
  char s[32];
  std::snprintf(s, sizeof s, v < 1 ? "%.3f" : v < 10 ? "%.2f" : "%.1f", v);  // sigmas go to ~0.01 mm
  return s;
}

// ?layer= (depth when absent) and the latest map's values of it, or false with the error sent.
bool requested_layer(HttpContext& ctx, const httplib::Request& req, httplib::Response& res, MapCopy& m,
                     app::DepthLayer& layer) {
  if (!only_params(req, res, {"layer"})) return false;
  const std::string name = req.has_param("layer") ? req.get_param_value("layer") : "depth";
  const auto parsed = app::depth_layer_from_string(name);
  if (!parsed) {
    send_error(res, 400, "bad_parameter", "layer must be depth, sigma or calib_sigma, got \"" + name + "\"");
    return false;
  }
  layer = *parsed;
  if (!latest_map(ctx, res, m, layer)) return false;
  // A map with depths but no calibration sigma had a calibration without a covariance (a map
  // without any depth has none to give either way: then the calibration in use decides).
  if (layer == app::DepthLayer::calib_sigma && !m.calib_sigma &&
      (m.valid_count > 0 || !ctx.pipeline->rig()->sigmas.covariance)) {
    send_error(res, 422, "no_calibration_covariance",
               "the calibration carries no covariance (the paper's files: marginal sigmas only), so there is "
               "no calibration sigma to give; `naneye calibrate` writes one");
    return false;
  }
  return true;
}

std::string file_name(app::DepthLayer layer) {
  return layer == app::DepthLayer::depth ? "depth" : app::to_string(layer);
}

}  // namespace

void add_depth_map_routes(httplib::Server& svr, HttpContext& ctx) {
  svr.Get("/v1/depth.png", [&ctx](const httplib::Request& req, httplib::Response& res) {
    MapCopy m;
    app::DepthLayer layer;
    if (!requested_layer(ctx, req, res, m, layer)) return;
    cv::Mat img;
    app::encode_depth_layer(m.values, m.width, m.height, layer, img);
    res.set_header("X-Naneye-Depth-Unit-Mm", "0.01");
    send_png(res, img, m.pair, file_name(layer));
  });

  svr.Get("/v1/depth/colour.png", [&ctx](const httplib::Request& req, httplib::Response& res) {
    MapCopy m;
    app::DepthLayer layer;
    if (!requested_layer(ctx, req, res, m, layer)) return;
    std::vector<float> valid;
    valid.reserve(m.values.size());
    for (float x : m.values)
      if (std::isfinite(x)) valid.push_back(x);
    double lo = 0, hi = 1;
    if (!valid.empty()) {
      auto quantile = [&valid](double q) {
        auto k = valid.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(valid.size() - 1));
        std::nth_element(valid.begin(), k, valid.end());
        return static_cast<double>(*k);
      };
      lo = quantile(kScaleLowQuantile);
      hi = quantile(kScaleHighQuantile);
      if (!(hi > lo)) hi = lo + 0.01;  // a flat map still gets a readable scale
    }
    cv::Mat img(m.height + kBarHeight, m.width, CV_8UC3, cv::Scalar(0, 0, 0));
    for (int v = 0; v < m.height; ++v)
      for (int u = 0; u < m.width; ++u) {
        const float x = m.values[static_cast<std::size_t>(v) * m.width + u];
        if (std::isfinite(x)) img.at<cv::Vec3b>(v, u) = turbo((x - lo) / (hi - lo));
      }
    // The bar: the scale's range left to right, labelled at both ends and in the middle (mm).
    const int x0 = 8, x1 = m.width - 8, y0 = m.height + 4, y1 = m.height + 14;
    for (int x = x0; x <= x1; ++x) {
      const cv::Vec3b c = turbo(static_cast<double>(x - x0) / (x1 - x0));
      cv::line(img, {x, y0}, {x, y1}, cv::Scalar(c[0], c[1], c[2]));
    }
    const cv::Scalar white(230, 230, 230);
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    const double scale = 0.35;
    const int ty = m.height + kBarHeight - 6;
    auto label = [&](const std::string& text, int x, int align) {  // align: -1 left, 0 centre, 1 right
      int base = 0;
      const cv::Size sz = cv::getTextSize(text, font, scale, 1, &base);
      const int left = align < 0 ? x : align == 0 ? x - sz.width / 2 : x - sz.width;
      cv::putText(img, text, {left, ty}, font, scale, white, 1, cv::LINE_AA);
    };
    if (valid.empty()) {
      label("no depth", m.width / 2, 0);
    } else {
      label(mm_label(lo), x0, -1);
      const char* what = layer == app::DepthLayer::depth   ? ""
                         : layer == app::DepthLayer::sigma ? "sigma "
                                                           : "calib sigma ";
      label(what + mm_label(0.5 * (lo + hi)) + " mm", m.width / 2, 0);
      label(mm_label(hi), x1, 1);
    }
    res.set_header("X-Naneye-Scale-Min-Mm", mm_label(lo));
    res.set_header("X-Naneye-Scale-Max-Mm", mm_label(hi));
    send_png(res, img, m.pair, file_name(layer) + "-colour");
  });
}

}  // namespace naneye::daemon::http
