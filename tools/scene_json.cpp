// The scene object for `naneye recon --scene`: the serializer naneyed uses too
// (recon/scene/scene_json.hpp), so the CLI and the daemon cannot drift apart.
#include "scene_json.hpp"

#include "naneye/recon/scene/scene_json.hpp"

namespace naneye::tools {

nlohmann::json scene_to_json(const recon::scene::SparseResult& r, const recon::scene::DepthMap* dense) {
  return recon::scene::scene_to_json(r,
                                     dense ? std::optional(recon::scene::summarize(*dense)) : std::nullopt);
}

}  // namespace naneye::tools
