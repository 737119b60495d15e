#pragma once
// The scene half of one pair's published result ([recon] mode scene or both, docs/scene.md): the
// sparse points in full and the dense map's summary. The dense map itself (500 kB a pair) is not
// copied into every held result: the pipeline publishes it in a few slots of its own, tagged with
// the same sequence number, so a reader can tell whether the map it finds belongs to its result.
#include <cstdint>

#include "naneye/app/scene_json.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::app {

struct SceneResult {
  bool computed = false;  // the scene path ran on this pair (false in board mode)
  recon::scene::SparseResult sparse;
  bool dense = false;  // a dense map was computed for this pair (`depth` holds its summary)
  DepthSummary depth;

  // Forgets the previous pair's scene, keeping the buffers' capacity.
  void clear() {
    computed = dense = false;
    sparse.points.clear();
    sparse.valid_count = 0;
    sparse.noise_sigma_dn = 0;
    depth = {};
  }
};

// A published dense map: the pair it was computed on and its result's sequence number.
struct DepthSlot {
  std::uint64_t seq = 0, pair = 0;
  recon::scene::DepthMap map;
};

}  // namespace naneye::app
