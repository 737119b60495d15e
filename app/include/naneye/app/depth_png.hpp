#pragma once
// The dense map's layers as 16-bit images (issue 14's format, one place for `naneye recon
// --depth-out` and naneyed's /v1/depth.png): 0.01 mm per unit on the left raw grid, 0 = none.
// - depth: a depth beyond 655.35 mm (none is searched) is left out, never clipped to a wrong value;
// - sigma, calib_sigma: a sigma below half a unit is written as 1 (0 keeps meaning "none"), one
//   beyond 655.35 mm as 65535 ("at least"), so every depth keeps a sigma.
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "naneye/recon/scene/dense.hpp"

namespace naneye::app {

enum class DepthLayer { depth, sigma, calib_sigma };

inline constexpr double kDepthPngUnitsPerMm = 100.0;

// "depth", "sigma", "calib_sigma"; empty for anything else.
std::optional<DepthLayer> depth_layer_from_string(std::string_view s);
const char* to_string(DepthLayer layer);

// The layer's values (row-major, width x height, mm, NaN = none) into `u16` (CV_16UC1, reused).
void encode_depth_layer(std::span<const float> mm, int width, int height, DepthLayer layer, cv::Mat& u16);
// The map's own vector for a layer.
const std::vector<float>& layer_values(const recon::scene::DepthMap& m, DepthLayer layer);

}  // namespace naneye::app
