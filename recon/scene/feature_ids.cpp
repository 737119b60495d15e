// Feature ids across pairs: whole-pixel pairing, the motion's median, sub-pixel verification
// (feature_ids.hpp).
#include "naneye/recon/scene/feature_ids.hpp"

#include <algorithm>
#include <cmath>

#include "interpolate.hpp"
#include "naneye/base/median.hpp"

namespace naneye::recon::scene {

FeatureIds::FeatureIds(int width, int height, int max_features, const FeatureIdSettings& s,
                       int detector_cell_px)
    : s_(s), w_(width), h_(height), cell_(std::max(1, s.max_motion_px)) {
  const int dc = std::max(1, detector_cell_px);
  detected_in_cell_.assign(static_cast<std::size_t>((w_ + dc - 1) / dc) * ((h_ + dc - 1) / dc), -1);
  cell_kept_.assign(detected_in_cell_.size(), 0);
  const auto n = static_cast<std::size_t>(std::max(0, max_features));
  prev_luma_.assign(static_cast<std::size_t>(w_) * h_, 0.f);
  prev_.reserve(n);
  next_.reserve(n);
  link_.assign(n, -1);
  head_.assign(static_cast<std::size_t>((w_ + cell_ - 1) / cell_) * ((h_ + cell_ - 1) / cell_), -1);
  // One candidate per feature at most (its best previous one).
  candidates_.reserve(n);
  cur_windows_.assign(n, Window{});
  const int mc = (w_ + s_.motion_cell_px - 1) / s_.motion_cell_px,
            mr = (h_ + s_.motion_cell_px - 1) / s_.motion_cell_px;
  motion_.assign(static_cast<std::size_t>(mc) * mr, Motion{});
  votes_x_.reserve(n);
  pair_dx_.assign(n, 0.f);
  pair_dy_.assign(n, 0.f);
  track_x_.assign(n, 0.f);
  track_y_.assign(n, 0.f);
  votes_y_.reserve(n);
  resampled_.assign(static_cast<std::size_t>((2 * s.radius + 1) * (2 * s.radius + 1)), 0.f);
  prev_taken_.assign(n, 0);
  feature_done_.assign(n, 0);
}

FeatureIds::Window FeatureIds::window(const GrayView& img, int u, int v) const {
  const int r = s_.radius;
  double sum = 0, sum2 = 0;
  for (int dr = -r; dr <= r; ++dr)
    for (int dc = -r; dc <= r; ++dc) {
      const double x = img.at(u + dc, v + dr);
      sum += x;
      sum2 += x * x;
    }
  const double n = (2.0 * r + 1) * (2.0 * r + 1);
  const double ss = sum2 - sum * sum / n;
  Window w;
  w.mean = static_cast<float>(sum / n);
  w.inv_norm = ss > 0 ? static_cast<float>(1.0 / std::sqrt(ss)) : 0.f;
  return w;
}

float FeatureIds::zncc(const GrayView& a, int ua, int va, const Window& wa, const GrayView& b, int ub, int vb,
                       const Window& wb) const {
  if (wa.inv_norm == 0 || wb.inv_norm == 0) return -1;
  const int r = s_.radius;
  double acc = 0;
  for (int dr = -r; dr <= r; ++dr) {
    const float* pa = a.data + (va + dr) * a.width + ua - r;
    const float* pb = b.data + (vb + dr) * b.width + ub - r;
    for (int k = 0; k <= 2 * r; ++k) acc += double(pa[k] - wa.mean) * (pb[k] - wb.mean);
  }
  return static_cast<float>(acc * wa.inv_norm * wb.inv_norm);
}

float FeatureIds::zncc_resampled(const GrayView& a, int ua, int va, const Window& wa, const GrayView& b,
                                 double xb, double yb) {
  const int r = s_.radius;
  // Written so that a NaN place fails it too.
  if (wa.inv_norm == 0 || !(xb - r >= 1 && yb - r >= 1 && xb + r < b.width - 3 && yb + r < b.height - 3))
    return -1;
  // Every sample of the window has the same fractional place: the weights once (computed per sample
  // they were ~9 M of the sparse path's ~190 M instructions per pair on a hand-held sequence), the
  // taps inside the image by the test above.
  const int c0 = static_cast<int>(xb), r0 = static_cast<int>(yb);
  float wx[4], wy[4];
  keys_weights(static_cast<float>(xb - c0), wx);
  keys_weights(static_cast<float>(yb - r0), wy);
  double sum = 0, sum2 = 0;
  std::size_t k = 0;
  for (int dr = -r; dr <= r; ++dr)
    for (int dc = -r; dc <= r; ++dc, ++k) {
      const float x = cubic_from_taps(b.data + (r0 + dr - 1) * b.width + (c0 + dc - 1), b.width, wx, wy);
      resampled_[k] = x;
      sum += x;
      sum2 += double(x) * x;
    }
  const double n = static_cast<double>(k), ss = sum2 - sum * sum / n;
  if (!(ss > 0)) return -1;
  const double mean = sum / n;
  double acc = 0;
  k = 0;
  for (int dr = -r; dr <= r; ++dr) {
    const float* pa = a.data + (va + dr) * a.width + ua - r;
    for (int c = 0; c <= 2 * r; ++c, ++k) acc += double(pa[c] - wa.mean) * (resampled_[k] - mean);
  }
  return static_cast<float>(acc * wa.inv_norm / std::sqrt(ss));
}

void FeatureIds::pair_whole_pixels(const GrayView& left, std::span<const Feature> tried) {
  const int cols = (w_ + cell_ - 1) / cell_;
  const GrayView prev{prev_luma_.data(), w_, h_};
  const int r2 = s_.max_motion_px * s_.max_motion_px;
  candidates_.clear();
  for (int k = 0; k < static_cast<int>(tried.size()); ++k) {
    const Feature& f = tried[static_cast<std::size_t>(k)];
    float best = -2, second = -2;
    int best_p = -1;
    const int bc = f.u / cell_, br = f.v / cell_;
    for (int rr = std::max(0, br - 1); rr <= br + 1 && rr * cell_ < h_; ++rr)
      for (int cc = std::max(0, bc - 1); cc <= bc + 1 && cc < cols; ++cc)
        for (int p = head_[static_cast<std::size_t>(rr) * cols + cc]; p >= 0;
             p = link_[static_cast<std::size_t>(p)]) {
          const Prev& q = prev_[static_cast<std::size_t>(p)];
          const int du = q.u - f.u, dv = q.v - f.v;
          if (du * du + dv * dv > r2) continue;
          const float z =
              zncc(left, f.u, f.v, cur_windows_[static_cast<std::size_t>(k)], prev, q.u, q.v, q.w);
          if (z > best) {
            second = best;
            best = z;
            best_p = p;
          } else if (z > second) {
            second = z;
          }
        }
    if (best_p < 0 || best < s_.min_zncc) continue;
    if (second > -2 && (1 - best) > s_.max_ambiguity * (1 - second)) continue;
    candidates_.push_back({best, k, best_p});
    // The pairing's own sub-pixel offset: a parabola through the ZNCC at the neighbouring whole-pixel
    // offsets in x and in y (each pairing is off by up to half a pixel per axis: features sit at
    // pixel centres, the motion does not).
    const Prev& q = prev_[static_cast<std::size_t>(best_p)];
    const Window& wk = cur_windows_[static_cast<std::size_t>(k)];
    const auto at = [&](int du, int dv) {
      const int u = q.u + du, v = q.v + dv;
      if (u - s_.radius < 0 || v - s_.radius < 0 || u + s_.radius >= w_ || v + s_.radius >= h_) return best;
      return zncc(left, f.u, f.v, wk, prev, u, v, window(prev, u, v));
    };
    const auto vertex = [](float m, float c, float p) {
      const float den = m - 2 * c + p;
      return den < 0 ? std::clamp(0.5f * (m - p) / den, -0.5f, 0.5f) : 0.f;
    };
    // Displacement current - previous: the previous point sits at q + (ox, oy).
    const float ox = vertex(at(-1, 0), best, at(1, 0)), oy = vertex(at(0, -1), best, at(0, 1));
    pair_dx_[static_cast<std::size_t>(k)] = static_cast<float>(f.u - q.u) - ox;
    pair_dy_[static_cast<std::size_t>(k)] = static_cast<float>(f.v - q.v) - oy;
  }
}

void FeatureIds::estimate_motion(std::span<const Feature> tried) {
  const int mc = (w_ + s_.motion_cell_px - 1) / s_.motion_cell_px;
  const int mr = static_cast<int>(motion_.size()) / mc;
  const auto vote = [&](const Candidate& c) {
    votes_x_.push_back(pair_dx_[static_cast<std::size_t>(c.feature)]);
    votes_y_.push_back(pair_dy_[static_cast<std::size_t>(c.feature)]);
  };
  votes_x_.clear();
  votes_y_.clear();
  for (const Candidate& c : candidates_) vote(c);
  Motion global;
  if (static_cast<int>(votes_x_.size()) >= s_.min_motion_votes)
    global = {base::upper_median(votes_x_), base::upper_median(votes_y_), true};
  for (int cr = 0; cr < mr; ++cr)
    for (int cc = 0; cc < mc; ++cc) {
      votes_x_.clear();
      votes_y_.clear();
      for (const Candidate& c : candidates_) {
        const Feature& f = tried[static_cast<std::size_t>(c.feature)];
        if (std::abs(f.u / s_.motion_cell_px - cc) <= 1 && std::abs(f.v / s_.motion_cell_px - cr) <= 1)
          vote(c);
      }
      Motion& m = motion_[static_cast<std::size_t>(cr) * mc + cc];
      m = static_cast<int>(votes_x_.size()) >= s_.min_motion_votes
              ? Motion{base::upper_median(votes_x_), base::upper_median(votes_y_), true}
              : global;
    }
}

void FeatureIds::bucket_previous() {
  const int cols = (w_ + cell_ - 1) / cell_;
  std::fill(head_.begin(), head_.end(), -1);
  for (int p = 0; p < static_cast<int>(prev_.size()); ++p) {
    const std::size_t b = static_cast<std::size_t>(prev_[p].v / cell_) * cols + prev_[p].u / cell_;
    link_[static_cast<std::size_t>(p)] = head_[b];
    head_[b] = p;
    prev_taken_[static_cast<std::size_t>(p)] = 0;
  }
}

void FeatureIds::keep_tracked(const GrayView& left, const FeatureDetector& det, const std::uint8_t* usable,
                              double noise_sigma, std::vector<Feature>& features) {
  if (!s_.keep_tracked || prev_.empty()) return;
  const std::span<const Feature> detected(features.data(), std::min(features.size(), cur_windows_.size()));
  bucket_previous();
  for (std::size_t k = 0; k < detected.size(); ++k)
    cur_windows_[k] = window(left, detected[k].u, detected[k].v);
  pair_whole_pixels(left, detected);
  estimate_motion(detected);
  motion_ready_ = true;
  const int cell = det.settings().cell_px, cols = (w_ + cell - 1) / cell, rows = (h_ + cell - 1) / cell;
  // Sized at construction for the detector's cells (another cell size: sized here, once).
  detected_in_cell_.assign(static_cast<std::size_t>(cols) * rows, -1);
  cell_kept_.assign(detected_in_cell_.size(), 0);
  for (std::size_t k = 0; k < detected.size(); ++k)
    detected_in_cell_[static_cast<std::size_t>(detected[k].v / cell) * cols + detected[k].u / cell] =
        static_cast<int>(k);
  const double need = det.min_eig_needed(noise_sigma);
  const GrayView prev{prev_luma_.data(), w_, h_};
  const int mc = (w_ + s_.motion_cell_px - 1) / s_.motion_cell_px;
  // In the previous pair's order (its own coarse-to-fine, strongest-first order): where two
  // predictions fall in one cell, the one tried first there keeps it.
  for (const Prev& q : prev_) {
    const Motion& m =
        motion_[static_cast<std::size_t>(q.v / s_.motion_cell_px) * mc + q.u / s_.motion_cell_px];
    if (!m.known) continue;
    const double x = q.x + m.dx, y = q.y + m.dy;
    const int u = static_cast<int>(std::lround(x)), v = static_cast<int>(std::lround(y));
    if (u < 0 || v < 0 || u >= w_ || v >= h_ || !usable[static_cast<std::size_t>(v) * w_ + u]) continue;
    const std::size_t c = static_cast<std::size_t>(v / cell) * cols + u / cell;
    const int k = detected_in_cell_[c];
    if (k < 0 || cell_kept_[c]) continue;  // no detection there passed the gate, or one is kept
    Feature& f = features[static_cast<std::size_t>(k)];
    if (std::hypot(f.u - x, f.v - y) <= s_.match_px) {  // already where the point went
      cell_kept_[c] = 1;
      continue;
    }
    const float lmin = det.min_eig_at(u, v);
    if (lmin < need || !(lmin > 0)) continue;
    // The same patch as the previous feature's (assign's pass-2 test, here before matching): where
    // the motion is a chance median (another scene, a cut), nothing replaces the cell's strongest.
    if (zncc_resampled(left, u, v, window(left, u, v), prev, u - m.dx, v - m.dy) < s_.verify_zncc) continue;
    f = Feature{u, v, lmin};
    cell_kept_[c] = 1;
  }
}

void FeatureIds::assign(const GrayView& left, std::span<const Feature> tried_all,
                        std::span<std::int64_t> ids) {
  const std::span<const Feature> tried = tried_all.first(std::min(tried_all.size(), ids.size()));
  const int n = static_cast<int>(tried.size());
  const int cols = (w_ + cell_ - 1) / cell_;
  const int mc = (w_ + s_.motion_cell_px - 1) / s_.motion_cell_px;
  const GrayView prev{prev_luma_.data(), w_, h_};
  bucket_previous();
  for (int k = 0; k < n; ++k) {
    const Feature& f = tried[static_cast<std::size_t>(k)];
    cur_windows_[static_cast<std::size_t>(k)] = window(left, f.u, f.v);
    feature_done_[static_cast<std::size_t>(k)] = 0;
  }
  candidates_.clear();
  if (!prev_.empty()) {
    // One motion per pair: keep_tracked's, over every detection, where it ran (the tried features
    // are a subset of them, some moved onto the previous points' places).
    if (!motion_ready_) {
      pair_whole_pixels(left, tried);
      estimate_motion(tried);
    }
    // Pass 2: the previous feature at the predicted place, verified on the resampled window.
    candidates_.clear();
    for (int k = 0; k < n; ++k) {
      const Feature& f = tried[static_cast<std::size_t>(k)];
      const Motion& m =
          motion_[static_cast<std::size_t>(f.v / s_.motion_cell_px) * mc + f.u / s_.motion_cell_px];
      if (!m.known) continue;
      const double x = f.u - m.dx, y = f.v - m.dy;
      int best_p = -1;
      double best_d = s_.match_px;
      const int bc = static_cast<int>(x) / cell_, br = static_cast<int>(y) / cell_;
      for (int rr = std::max(0, br - 1); rr <= br + 1 && rr * cell_ < h_; ++rr)
        for (int cc = std::max(0, bc - 1); cc <= bc + 1 && cc < cols; ++cc)
          for (int p = head_[static_cast<std::size_t>(rr) * cols + cc]; p >= 0;
               p = link_[static_cast<std::size_t>(p)]) {
            const Prev& q = prev_[static_cast<std::size_t>(p)];
            const double d = std::hypot(q.x - x, q.y - y);
            if (d <= best_d) {
              best_d = d;
              best_p = p;
            }
          }
      if (best_p < 0) continue;
      const float z = zncc_resampled(left, f.u, f.v, cur_windows_[static_cast<std::size_t>(k)], prev, x, y);
      if (z >= s_.verify_zncc) candidates_.push_back({z, k, best_p});
    }
  }
  // Best scores first: a previous feature goes to the feature that matches it best.
  std::sort(candidates_.begin(), candidates_.end(), [](const Candidate& a, const Candidate& b) {
    return a.zncc != b.zncc ? a.zncc > b.zncc : a.feature < b.feature;
  });
  for (const Candidate& c : candidates_) {
    auto& taken = prev_taken_[static_cast<std::size_t>(c.prev)];
    if (taken) continue;
    taken = 1;
    const Prev& q = prev_[static_cast<std::size_t>(c.prev)];
    const Feature& f = tried[static_cast<std::size_t>(c.feature)];
    const Motion& m =
        motion_[static_cast<std::size_t>(f.v / s_.motion_cell_px) * mc + f.u / s_.motion_cell_px];
    ids[static_cast<std::size_t>(c.feature)] = q.id;
    track_x_[static_cast<std::size_t>(c.feature)] = q.x + m.dx;
    track_y_[static_cast<std::size_t>(c.feature)] = q.y + m.dy;
    feature_done_[static_cast<std::size_t>(c.feature)] = 1;
  }
  next_.clear();
  for (int k = 0; k < n; ++k) {
    const Feature& f = tried[static_cast<std::size_t>(k)];
    if (!feature_done_[static_cast<std::size_t>(k)]) {
      ids[static_cast<std::size_t>(k)] = next_id_++;
      track_x_[static_cast<std::size_t>(k)] = static_cast<float>(f.u);
      track_y_[static_cast<std::size_t>(k)] = static_cast<float>(f.v);
    }
    next_.push_back({f.u, f.v, ids[static_cast<std::size_t>(k)], cur_windows_[static_cast<std::size_t>(k)],
                     track_x_[static_cast<std::size_t>(k)], track_y_[static_cast<std::size_t>(k)]});
  }
  motion_ready_ = false;
  prev_.swap(next_);
  std::copy(left.data, left.data + static_cast<std::size_t>(w_) * h_, prev_luma_.begin());
}

}  // namespace naneye::recon::scene
