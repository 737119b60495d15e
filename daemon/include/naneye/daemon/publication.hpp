#pragma once
// Publication: what HTTP threads read, and the worker's hand-over into it. Three sets of pinned
// slots (pinned_slots.hpp): the results, a copy of the latest frames every
// frame_snapshot_interval_ms, and the dense maps, each tagged with its result's sequence number.
// Every buffer is sized at construction, so the worker allocates nothing per pair; when every slot
// is pinned by readers the worker writes into a scratch slot instead (the result is computed, not
// published) and never waits. A dense map is published before the result that refers to it, so a
// reader of result `seq` finds its map while it is held.
//
// Threads: begin(), publish() and offer_frames() are the worker's; the slots are read from any thread.
#include <array>
#include <cstddef>
#include <cstdint>

#include "naneye/app/processor.hpp"
#include "naneye/app/scene_result.hpp"
#include "naneye/daemon/pinned_slots.hpp"
#include "naneye/driver/frame.hpp"
#include "naneye/recon/pair/result.hpp"

namespace naneye::daemon {

// One published result with the times the service adds to it.
struct Published {
  recon::PairResult result;
  app::SceneResult scene;         // empty (computed = false) in [recon] mode board
  std::uint64_t seq = 0;          // 1, 2, 3... per processed pair: the /v1/events id
  std::int64_t capture_ns = 0;    // CLOCK_MONOTONIC when the pair's last record arrived
  std::int64_t published_ns = 0;  // CLOCK_MONOTONIC when it was published
  std::int64_t recon_ns = 0;      // time spent in the processor
};

// The latest frames, copied every frame_snapshot_interval_ms for /v1/frames (not every pair).
struct FrameSnapshot {
  std::uint64_t seq = 0, pair = 0;
  driver::ColorMode color = driver::ColorMode::mono;
  std::array<std::uint16_t, driver::kPixelCount> left{}, right{};
  int corners = 0;
  std::array<Eigen::Vector2d, recon::kMaxCorners> left_px{}, right_px{};
};

class Publication {
 public:
  // `history` results are kept for readers (plus two being written and read); `processor` sizes
  // every slot's buffers.
  Publication(std::size_t history, int frame_snapshot_interval_ms, const app::PairProcessor& processor);
  Publication(const Publication&) = delete;
  Publication& operator=(const Publication&) = delete;

  // Where the worker writes one pair: a result slot (or the scratch one) and, with a dense
  // processor, a map slot (or the scratch map).
  struct Write {
    Published* result = nullptr;
    app::DepthSlot* depth = nullptr;  // null when the processor makes no dense map
    bool publishable = false;         // result is a slot, not the scratch
  };
  Write begin(bool dense);
  // Tags and publishes the map (if the result has one), then the result as `seq` (stamping its
  // published_ns). False when it went to the scratch slot: computed, not published.
  bool publish(const Write& w, std::uint64_t seq, std::uint64_t pair_index);
  // Copies the pair's frames and corners for /v1/frames when the interval is up (and a slot is free).
  void offer_frames(const Published& result, const driver::StereoPair& pair);

  const PinnedSlots<Published>& results() const { return results_; }
  const PinnedSlots<FrameSnapshot>& frames() const { return frames_; }
  const PinnedSlots<app::DepthSlot>& depth_maps() const { return depth_maps_; }

 private:
  std::int64_t frame_interval_ns_;
  PinnedSlots<Published> results_;
  PinnedSlots<FrameSnapshot> frames_;
  PinnedSlots<app::DepthSlot> depth_maps_;
  Published scratch_;             // used when every slot is pinned, so processing never waits
  app::DepthSlot depth_scratch_;  // the same for the dense map
  std::int64_t last_frames_ns_ = 0;
};

}  // namespace naneye::daemon
