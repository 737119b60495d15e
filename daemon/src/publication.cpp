#include "naneye/daemon/publication.hpp"

#include "naneye/base/clock.hpp"

namespace naneye::daemon {

Publication::Publication(std::size_t history, int frame_snapshot_interval_ms,
                         const app::PairProcessor& processor)
    : frame_interval_ns_(std::int64_t{frame_snapshot_interval_ms} * 1'000'000),
      results_(history + 2),
      // A PNG encode pins a frame slot for a few ms; four slots keep the worker from ever skipping.
      frames_(4),
      // A PNG of the map pins a slot for a few ms, /v1/depth/at for microseconds; a result's map is
      // looked up right after the result, so 4 slots keep it findable while pairs come at 62 fps.
      depth_maps_(4) {
  results_.prepare([&processor](Published& p) { processor.reserve(p.scene, nullptr); });
  processor.reserve(scratch_.scene, &depth_scratch_.map);
  if (processor.dense())
    depth_maps_.prepare([this, &processor](app::DepthSlot& d) { processor.reserve(scratch_.scene, &d.map); });
}

Publication::Write Publication::begin(bool dense) {
  Write w;
  w.result = results_.begin_write();
  w.publishable = w.result != nullptr;
  if (!w.publishable) w.result = &scratch_;
  if (dense) {
    w.depth = depth_maps_.begin_write();
    if (!w.depth)
      w.depth = &depth_scratch_;  // every map pinned: computed (it is part of the result), not held
  }
  return w;
}

bool Publication::publish(const Write& w, std::uint64_t seq, std::uint64_t pair_index) {
  if (w.depth && w.depth != &depth_scratch_) {
    w.depth->seq = seq;
    w.depth->pair = pair_index;
    // Published before the result that refers to it: a reader of result `seq` finds its map.
    if (w.result->scene.dense)
      depth_maps_.publish(seq);
    else
      depth_maps_.abandon();
  }
  w.result->seq = seq;
  w.result->published_ns = base::monotonic_ns();
  if (w.publishable) results_.publish(seq);
  return w.publishable;
}

void Publication::offer_frames(const Published& r, const driver::StereoPair& pair) {
  if (r.published_ns - last_frames_ns_ < frame_interval_ns_) return;
  FrameSnapshot* f = frames_.begin_write();
  if (!f) return;
  f->seq = r.seq;
  f->pair = pair.index;
  f->color = pair.left.color;
  f->left = pair.left.pixels;
  f->right = pair.right.pixels;
  f->corners = r.result.point_count;
  for (int i = 0; i < f->corners; ++i) {
    f->left_px[static_cast<std::size_t>(i)] = r.result.points[static_cast<std::size_t>(i)].left_px;
    f->right_px[static_cast<std::size_t>(i)] = r.result.points[static_cast<std::size_t>(i)].right_px;
  }
  frames_.publish(r.seq);
  last_frames_ns_ = r.published_ns;
}

}  // namespace naneye::daemon
