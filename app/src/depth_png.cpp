#include "naneye/app/depth_png.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace naneye::app {

std::optional<DepthLayer> depth_layer_from_string(std::string_view s) {
  if (s == "depth") return DepthLayer::depth;
  if (s == "sigma") return DepthLayer::sigma;
  if (s == "calib_sigma") return DepthLayer::calib_sigma;
  return std::nullopt;
}

const char* to_string(DepthLayer layer) {
  switch (layer) {
    case DepthLayer::depth:
      return "depth";
    case DepthLayer::sigma:
      return "sigma";
    case DepthLayer::calib_sigma:
      return "calib_sigma";
  }
  return "?";
}

const std::vector<float>& layer_values(const recon::scene::DepthMap& m, DepthLayer layer) {
  switch (layer) {
    case DepthLayer::sigma:
      return m.sigma_mm;
    case DepthLayer::calib_sigma:
      return m.calib_sigma_mm;
    case DepthLayer::depth:
      break;
  }
  return m.z_mm;
}

void encode_depth_layer(std::span<const float> mm, int width, int height, DepthLayer layer, cv::Mat& u16) {
  u16.create(height, width, CV_16UC1);
  const bool depth = layer == DepthLayer::depth;
  for (int r = 0; r < height; ++r) {
    auto* row = u16.ptr<std::uint16_t>(r);
    for (int c = 0; c < width; ++c) {
      const float v = mm[static_cast<std::size_t>(r) * width + c];
      const double units = std::isfinite(v) ? std::round(v * kDepthPngUnitsPerMm) : 0.0;
      if (!std::isfinite(v) || !(v > 0))
        row[c] = 0;
      else if (depth)
        row[c] = units >= 1 && units <= 65535 ? static_cast<std::uint16_t>(units) : 0;
      else
        row[c] = static_cast<std::uint16_t>(std::clamp(units, 1.0, 65535.0));
    }
  }
}

}  // namespace naneye::app
