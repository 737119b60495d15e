#pragma once
// The "scene" object of issue 14 for one pair's sparse reconstruction (docs/scene.md):
// {"points": [{"id", "left_px", "right_px", "xyz_mm", "depth_sigma_mm", "valid", "status"}],
//  "depth": {"valid_share", "median_mm"} or null while there is no dense map}.
#include <nlohmann/json.hpp>

#include "naneye/recon/scene/sparse.hpp"

namespace naneye::tools {

nlohmann::json scene_to_json(const recon::scene::SparseResult& r);

}  // namespace naneye::tools
