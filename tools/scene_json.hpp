#pragma once
// The "scene" object of issue 14 for one pair (docs/scene.md), by the serializer naneyed uses too
// (recon/scene/scene_json.hpp):
// {"points": [{"id", "left_px", "right_px", "xyz_mm", "depth_sigma_mm", "valid", "status"}],
//  "depth": {"valid_share", "median_mm", "valid_pixels", "visible_pixels"} of the dense map, or null
//  without one}.
#include <nlohmann/json.hpp>

#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::tools {

nlohmann::json scene_to_json(const recon::scene::SparseResult& r,
                             const recon::scene::DepthMap* dense = nullptr);

}  // namespace naneye::tools
