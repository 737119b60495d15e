// Serialises a sparse scene result (scene_json.hpp). Numbers only where the point is valid: a flagged
// point carries null coordinates and its reason, never a guess.
#include "scene_json.hpp"

#include <cmath>

namespace naneye::tools {

nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const recon::scene::DepthMap* dense) {
  nlohmann::json points = nlohmann::json::array();
  for (const auto& p : r.points) {
    nlohmann::json q;
    q["id"] = p.id;
    q["left_px"] = {p.left_px.x(), p.left_px.y()};
    q["valid"] = p.valid();
    q["status"] = recon::scene::to_string(p.status);
    if (p.valid()) {
      q["right_px"] = {p.right_px.x(), p.right_px.y()};
      q["xyz_mm"] = {p.X.x(), p.X.y(), p.X.z()};
      q["depth_sigma_mm"] = p.depth_sigma_mm;
    } else {
      q["right_px"] = nullptr;
      q["xyz_mm"] = nullptr;
      q["depth_sigma_mm"] = nullptr;
    }
    points.push_back(std::move(q));
  }
  nlohmann::json j;
  j["points"] = std::move(points);
  j["valid_points"] = r.valid_count;
  j["noise_sigma_dn"] = r.noise_sigma_dn;
  // No coverage figure without a dense map to stand behind it.
  j["depth"] = nullptr;
  if (dense) {
    // valid_share: of the pixels both eyes can see (DepthMap::visible_count); median of the valid.
    j["depth"] = {{"valid_share", dense->valid_share},
                  {"median_mm", std::isfinite(dense->median_mm) ? nlohmann::json(dense->median_mm) : nullptr},
                  {"valid_pixels", dense->valid_count},
                  {"visible_pixels", dense->visible_count}};
  }
  return j;
}

}  // namespace naneye::tools
