// Serialises one pair's scene (scene_json.hpp). Numbers only where they can be stood behind: a
// flagged point carries null coordinates and its reason, a map with no depth a null median.
#include "naneye/app/scene_json.hpp"

#include <cmath>

#include "naneye/app/json_number.hpp"

namespace naneye::app {

DepthSummary summarize(const recon::scene::DepthMap& m) {
  return {m.valid_count, m.visible_count, m.valid_share, m.median_mm, m.calib_sigma_median_mm};
}

nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const std::optional<DepthSummary>& depth) {
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
      q["calib_sigma_mm"] = finite_or_null(p.calib_sigma_mm);
    } else {
      q["right_px"] = nullptr;
      q["xyz_mm"] = nullptr;
      q["depth_sigma_mm"] = nullptr;
      q["calib_sigma_mm"] = nullptr;
    }
    points.push_back(std::move(q));
  }
  nlohmann::json j;
  j["points"] = std::move(points);
  j["valid_points"] = r.valid_count;
  j["noise_sigma_dn"] = r.noise_sigma_dn;
  if (depth) {
    j["depth"] = {{"valid_share", depth->valid_share},
                  {"median_mm", finite_or_null(depth->median_mm)},
                  {"calib_sigma_median_mm", finite_or_null(depth->calib_sigma_median_mm)},
                  {"valid_pixels", depth->valid_count},
                  {"visible_pixels", depth->visible_count}};
  } else {
    j["depth"] = nullptr;  // no dense map for this pair: no coverage figure to stand behind
  }
  return j;
}

nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const recon::scene::DepthMap* dense) {
  return scene_to_json(r, dense ? std::optional(summarize(*dense)) : std::nullopt);
}

}  // namespace naneye::app
