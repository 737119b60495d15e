#pragma once
// Stable ids for scene features across pairs ("a stable id per feature tracked across
// frames so a client can follow a point"). Features are detected afresh in every left frame (at
// pixel centres, one per grid cell), so a feature keeps an id only when it is shown to be the same
// scene point as a feature of the previous pair, in two passes:
//  1. each feature's best previous feature within max_motion_px by window ZNCC (whole pixels), kept
//     when unambiguous, and its sub-pixel offset from a parabola through the neighbouring ZNCCs:
//     these give the image motion, a median over each neighbourhood (the motion of a moving camera
//     is smooth across the image; a wrong pairing does not move a median);
//  2. each feature's place in the previous frame predicted by that motion (sub-pixel): it inherits
//     the id of the previous feature whose id's point (sub-pixel, carried by the motion from where
//     the id began) lies within match_px of that place when the windows, the previous one
//     resampled there, agree (ZNCC >= verify_zncc), best agreement first, one each.
// Otherwise it gets a new id: an id is never guessed, so one id is one scene point while it lives.
// keep_tracked, before matching, makes the detections follow the previous pair's points, so that
// the ids live on (docs/scene.md, "Keeping what is tracked, and the id's own point").
#include <cstdint>
#include <span>
#include <vector>

#include "naneye/recon/scene/features.hpp"

namespace naneye::recon::scene {

struct FeatureIdSettings {
  // px; the farthest a feature's left pixel may move between two consecutive pairs and keep its id.
  // A hand-held endoscope tip at camera rate (62 fps) moves its image by ~1-3 px per frame; a larger
  // jump starts new ids instead of risking a wrong one.
  int max_motion_px = 6;
  int radius = 4;  // px; the window compared: the sparse matcher's LK template (lk_affine.hpp)
  // Pass 1, whole-pixel windows (a sub-pixel offset lowers the ZNCC of the same patch): the bar of the
  // sparse path's coarse match (sparse.hpp, min_zncc) with its ambiguity rule.
  double min_zncc = 0.7;
  double max_ambiguity = 0.5;  // (1 - best) must be <= this share of (1 - second best)
  int motion_cell_px = 32;     // px; the motion is a median over the 3 x 3 cells of this size around
  int min_motion_votes = 8;    // fewer pass-1 pairings than this around a feature: the global median;
                               // fewer in the whole image: no motion, every id is new
  // Pass 2: px; a detection this close to the predicted place is the same point (a feature sits at a
  // pixel centre, so the true place is within 0.71 px of it; the motion's own error adds the rest).
  double match_px = 1.0;
  // The same patch resampled at its sub-pixel place, two frames of one camera: only noise and a
  // little warp differ; the sparse path's bar for a refined match (sparse.hpp, min_final_zncc).
  double verify_zncc = 0.9;
  // keep_tracked (below): a previous feature's predicted pixel becomes its cell's feature when it
  // passes the detector's gate. Off: every cell's strongest pixel, the ids following what they can.
  bool keep_tracked = true;
};

class FeatureIds {
 public:
  // `max_features`: the most features a pair can have (buffers are sized once); `detector_cell_px`:
  // the cell of the detector whose features keep_tracked is given (FeatureSettings::cell_px).
  FeatureIds(int width, int height, int max_features, const FeatureIdSettings& s = {},
             int detector_cell_px = FeatureSettings{}.cell_px);
  // Writes ids[k] for tried[k] (same length; every window of `radius` around a feature lies in the
  // image) and remembers this pair for the next call. Allocation-free.
  void assign(const GrayView& left, std::span<const Feature> tried, std::span<std::int64_t> ids);
  // Before matching, on this pair's detections (one per cell, FeatureDetector::detect, which must
  // have run on `left`): where a feature of the previous pair is predicted (the motion of pass 1,
  // over these detections; assign then takes it: one motion per pair) at a pixel whose window
  // passes the detector's gate and is usable, that pixel replaces its cell's detection, unless the
  // detection already sits within match_px of the prediction. The cell's strongest pixel moves from
  // one spot of the texture to another as the image moves (a 7 x 7 cell's argmax of lambda_min), and
  // each move ended an id; kept, the point is re-detected where assign will find it. Allocation-free
  // once warm.
  void keep_tracked(const GrayView& left, const FeatureDetector& det, const std::uint8_t* usable,
                    double noise_sigma, std::vector<Feature>& features);
  // Forget the previous pair (a new source, a seek): every feature gets a new id.
  void reset() {
    prev_.clear();
    motion_ready_ = false;
  }
  const FeatureIdSettings& settings() const { return s_; }

 private:
  struct Window {
    float mean = 0, inv_norm = 0;  // of the (2 radius + 1)^2 window; inv_norm 0: flat
  };
  struct Prev {
    int u, v;  // the feature's pixel
    std::int64_t id;
    Window w;
    // px; the id's own point in that frame, carried by the motion from where the id began: the
    // feature is the pixel centre nearest it, and the id follows the point, not the pixels (chained
    // roundings would walk ~0.4 px a frame).
    float x, y;
  };
  struct Candidate {
    float zncc;
    int feature, prev;
  };
  struct Motion {
    float dx = 0, dy = 0;  // current - previous, px
    bool known = false;
  };
  Window window(const GrayView& img, int u, int v) const;
  float zncc(const GrayView& a, int ua, int va, const Window& wa, const GrayView& b, int ub, int vb,
             const Window& wb) const;
  // ZNCC of a's window at (ua, va) with b resampled (cubic) around (xb, yb); -1 when it leaves b.
  float zncc_resampled(const GrayView& a, int ua, int va, const Window& wa, const GrayView& b, double xb,
                       double yb);
  void bucket_previous();
  void pair_whole_pixels(const GrayView& left, std::span<const Feature> tried);
  void estimate_motion(std::span<const Feature> tried);

  FeatureIdSettings s_;
  int w_, h_, cell_;
  std::vector<float> prev_luma_;
  std::vector<Prev> prev_, next_;
  std::vector<int> head_, link_;  // previous features bucketed by cell_ x cell_ cells
  std::vector<Candidate> candidates_;
  std::vector<Motion> motion_;  // per motion cell
  std::vector<float> votes_x_, votes_y_, resampled_;
  std::vector<float> pair_dx_, pair_dy_;  // per feature: its pass-1 pairing's sub-pixel displacement
  std::vector<float> track_x_, track_y_;  // per feature: its id's point (Prev::x, y) in this frame
  std::vector<Window> cur_windows_;
  std::vector<std::uint8_t> prev_taken_, feature_done_;
  std::vector<int> detected_in_cell_;  // keep_tracked: per detector cell, its feature's index or -1
  std::vector<std::uint8_t> cell_kept_;
  std::int64_t next_id_ = 0;
  bool motion_ready_ = false;  // keep_tracked estimated this pair's motion: assign takes it
};

}  // namespace naneye::recon::scene
