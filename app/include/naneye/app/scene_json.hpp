#pragma once
// The "scene" object of issue 14 (docs/scene.md), one serializer for `naneye recon --scene` and
// naneyed's /v1/depth so the two cannot drift apart:
// {"points": [{"id", "left_px", "right_px", "xyz_mm", "depth_sigma_mm", "calib_sigma_mm", "valid",
//              "status"}],
//  "valid_points", "noise_sigma_dn",
//  "depth": {"valid_share", "median_mm", "calib_sigma_median_mm", "valid_pixels", "visible_pixels"} or
//           null without a dense map}.
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::app {

// What the JSON says of a dense map (the map itself goes out as a PNG).
struct DepthSummary {
  int valid_count = 0;    // pixels with a depth
  int visible_count = 0;  // pixels both eyes can see
  double valid_share = 0;
  double median_mm = std::numeric_limits<double>::quiet_NaN();  // NaN when no pixel has a depth
  // Of the depths' calibration sigmas (DepthMap::calib_sigma_mm); NaN without a covariance.
  double calib_sigma_median_mm = std::numeric_limits<double>::quiet_NaN();
};

DepthSummary summarize(const recon::scene::DepthMap& m);

nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const std::optional<DepthSummary>& depth);
// The same with the summary of `dense` (null "depth" without one).
nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const recon::scene::DepthMap* dense);

}  // namespace naneye::app
