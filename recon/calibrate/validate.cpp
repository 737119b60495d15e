// Cross-validation of a calibration (the paper's Sec. "Evaluation Based on Cross-Validation"): calibrate
// on some views, reconstruct the others with the result; and the odd/even split that checks the sigmas:
// two independent estimates should differ by about sqrt(sigma_a^2 + sigma_b^2).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "naneye/base/median.hpp"
#include "naneye/recon/calibrate/calibrate.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/geometry/metrics.hpp"
#include "naneye/recon/geometry/triangulation.hpp"

namespace naneye::recon {
namespace {

// The view's corners as a full row-major grid seen by both eyes, or false.
bool full_grid(const CalibrationView& v, const BoardGeometry& board, std::vector<Eigen::Vector2d>& left,
               std::vector<Eigen::Vector2d>& right) {
  const std::size_t count = static_cast<std::size_t>(board.rows * board.cols);
  if (v.left.size() != count || v.right.size() != count) return false;
  left.assign(count, Eigen::Vector2d::Constant(NAN));
  right.assign(count, Eigen::Vector2d::Constant(NAN));
  auto place = [&](const std::vector<BoardCorner>& corners, std::vector<Eigen::Vector2d>& out) {
    for (const BoardCorner& c : corners) {
      if (c.row < 0 || c.row >= board.rows || c.col < 0 || c.col >= board.cols) return false;
      out[static_cast<std::size_t>(c.row * board.cols + c.col)] = c.px;
    }
    return std::all_of(out.begin(), out.end(), [](const Eigen::Vector2d& p) { return p.allFinite(); });
  };
  return place(v.left, left) && place(v.right, right);
}

HeldOutView evaluate_view(const StereoRig& rig, const CalibrationView& v, const BoardGeometry& board,
                          int index) {
  HeldOutView h;
  h.view = index;
  std::vector<Eigen::Vector2d> left, right;
  full_grid(v, board, left, right);
  std::vector<Eigen::Vector3d> X(left.size());
  for (std::size_t i = 0; i < left.size(); ++i) {
    // The corner sigma only scales the reported depth sigma, which is not used here.
    const Triangulated t = triangulate(rig, left[i], right[i], TriangulationMethod::refined, 0.1);
    X[i] = t.X;
    h.points += t.ok();
  }
  h.planarity_mm = planarity_error(X).value_or(NAN);
  h.distance_mm = distance_error(X, board.rows, board.cols, board.square_mm).value_or(NAN);
  h.reprojection_px = reprojection_error(rig, X, left, right).value_or(NAN);
  return h;
}

}  // namespace

SplitValidation cross_validate_splits(std::span<const CalibrationView> views, const BoardGeometry& board,
                                      const CalibrationSettings& settings, int splits, int train_views,
                                      unsigned seed) {
  SplitValidation out;
  std::vector<int> order(views.size());
  std::iota(order.begin(), order.end(), 0);
  int good = 0;
  for (int s = 0; s < splits; ++s) {
    SplitResult split;
    std::mt19937 rng(seed + static_cast<unsigned>(s));
    std::shuffle(order.begin(), order.end(), rng);
    const int n_train = std::min<int>(train_views, static_cast<int>(views.size()));
    split.train.assign(order.begin(), order.begin() + n_train);
    std::sort(split.train.begin(), split.train.end());
    std::vector<CalibrationView> train;
    for (int i : split.train) train.push_back(views[static_cast<std::size_t>(i)]);
    std::vector<Eigen::Vector2d> l, r;
    for (std::size_t i = static_cast<std::size_t>(n_train); i < order.size(); ++i)
      if (full_grid(views[static_cast<std::size_t>(order[i])], board, l, r)) split.test.push_back(order[i]);
    std::sort(split.test.begin(), split.test.end());
    const CalibrationResult cal = calibrate_stereo(train, board, settings);
    if (!cal.ok) {
      split.message = "calibration failed: " + cal.message;
    } else if (split.test.empty()) {
      split.message = "no held-out view shows the full board to both eyes";
    } else {
      split.ok = true;
      split.calibration_rms_px = cal.rms_px;
      double sums[3] = {0, 0, 0};
      int counts[3] = {0, 0, 0};
      for (int i : split.test) {
        const HeldOutView h = evaluate_view(cal.rig, views[static_cast<std::size_t>(i)], board, i);
        split.held_out.push_back(h);
        const double vals[3] = {h.planarity_mm, h.distance_mm, h.reprojection_px};
        for (int m = 0; m < 3; ++m)
          if (std::isfinite(vals[m])) sums[m] += vals[m], ++counts[m];
      }
      split.planarity_mm = counts[0] ? sums[0] / counts[0] : NAN;
      split.distance_mm = counts[1] ? sums[1] / counts[1] : NAN;
      split.reprojection_px = counts[2] ? sums[2] / counts[2] : NAN;
      out.planarity_mm += split.planarity_mm;
      out.distance_mm += split.distance_mm;
      out.reprojection_px += split.reprojection_px;
      ++good;
    }
    out.splits.push_back(std::move(split));
  }
  if (good) {
    out.planarity_mm /= good;
    out.distance_mm /= good;
    out.reprojection_px /= good;
  } else {
    out.planarity_mm = out.distance_mm = out.reprojection_px = NAN;
  }
  return out;
}

namespace {

// Every corner both eyes saw in any view, triangulated (refined) with rigs a and b, against the
// depth sigmas each rig's covariance allows (and their marginals taken as independent).
struct DepthComparison {
  bool ok = false;
  double sum = 0, sum_independent = 0;  // of (dZ / combined sigma)^2
  std::vector<double> relative, sigma_relative;
  double ratio_rms() const { return std::sqrt(sum / static_cast<double>(relative.size())); }
};

DepthComparison compare_depths(std::span<const CalibrationView> views, const StereoRig& rig_a,
                               const StereoRig& rig_b) {
  DepthComparison out;
  const auto a_u = CalibrationUncertainty::of(rig_a), b_u = CalibrationUncertainty::of(rig_b);
  const auto a_ind = CalibrationUncertainty::assuming_independent_sigmas(rig_a);
  const auto b_ind = CalibrationUncertainty::assuming_independent_sigmas(rig_b);
  if (!a_u || !b_u || !a_ind || !b_ind) return out;
  for (const CalibrationView& v : views)
    for (const BoardCorner& l : v.left)
      for (const BoardCorner& r : v.right) {
        if (r.row != l.row || r.col != l.col) continue;
        const Triangulated a = triangulate(rig_a, l.px, r.px, TriangulationMethod::refined, 0.0);
        const Triangulated b = triangulate(rig_b, l.px, r.px, TriangulationMethod::refined, 0.0);
        if (!a.ok() || !b.ok()) continue;
        const double dz = a.X.z() - b.X.z(), z = 0.5 * (a.X.z() + b.X.z());
        const double combined = std::hypot(a_u->depth_sigma_mm(a.X), b_u->depth_sigma_mm(b.X));
        out.sum += (dz / combined) * (dz / combined);
        out.sum_independent +=
            std::pow(dz / std::hypot(a_ind->depth_sigma_mm(a.X), b_ind->depth_sigma_mm(b.X)), 2);
        out.relative.push_back(std::abs(dz) / z);
        out.sigma_relative.push_back(combined / z);
      }
  out.ok = !out.relative.empty();
  return out;
}

// The two halvings by view index mod 4 beside odd/even (OddEvenValidation): {0, 1} against {2, 3},
// and {0, 3} against {1, 2}.
bool in_first_half(std::size_t i, int halving) {
  const std::size_t m = i % 4;
  return halving == 0 ? (m == 0 || m == 1) : (m == 0 || m == 3);
}

// The depth test of odd/even (out.odd, out.even) and of the two other halvings, pooled.
void compare_halvings(std::span<const CalibrationView> views, const BoardGeometry& board,
                      const CalibrationSettings& settings, OddEvenValidation& out) {
  const DepthComparison oe = compare_depths(views, out.odd.rig, out.even.rig);
  if (!oe.ok) return;
  out.depth_corners = static_cast<int>(oe.relative.size());
  out.depth_ratio_rms = oe.ratio_rms();
  out.depth_ratio_rms_independent = std::sqrt(oe.sum_independent / static_cast<double>(oe.relative.size()));
  out.depth_median_relative = base::upper_median(std::vector<double>(oe.relative));
  out.depth_sigma_median_relative = base::upper_median(std::vector<double>(oe.sigma_relative));
  out.split_depth_ratio_rms = {out.depth_ratio_rms};
  double sum = oe.sum;
  std::size_t corners = oe.relative.size();
  for (int halving = 0; halving < 2; ++halving) {
    std::vector<CalibrationView> halves[2];
    for (std::size_t i = 0; i < views.size(); ++i)
      halves[in_first_half(i, halving) ? 0 : 1].push_back(views[i]);
    const CalibrationResult a = calibrate_stereo(halves[0], board, settings);
    const CalibrationResult b = calibrate_stereo(halves[1], board, settings);
    if (!a.ok || !b.ok) continue;  // too few views in a half: the splits that calibrated decide
    const DepthComparison c = compare_depths(views, a.rig, b.rig);
    if (!c.ok) continue;
    out.split_depth_ratio_rms.push_back(c.ratio_rms());
    sum += c.sum;
    corners += c.relative.size();
  }
  out.pooled_depth_corners = static_cast<int>(corners);
  out.pooled_depth_ratio_rms = std::sqrt(sum / static_cast<double>(corners));
  if (out.pooled_depth_ratio_rms > kHonestDepthRatioRmsMax) out.sigma_scale = out.pooled_depth_ratio_rms;
}

}  // namespace

OddEvenValidation cross_validate_odd_even(std::span<const CalibrationView> views, const BoardGeometry& board,
                                          const CalibrationSettings& settings) {
  OddEvenValidation out;
  std::vector<CalibrationView> halves[2];
  for (std::size_t i = 0; i < views.size(); ++i) halves[i % 2].push_back(views[i]);
  out.even = calibrate_stereo(halves[0], board, settings);
  out.odd = calibrate_stereo(halves[1], board, settings);
  if (!out.even.ok || !out.odd.ok) {
    out.message = !out.odd.ok ? "odd views: " + out.odd.message : "even views: " + out.even.message;
    return out;
  }
  double sum = 0;
  int free = 0;
  for (std::size_t p = 0; p < out.odd.parameters.size(); ++p) {
    const ParameterEstimate &a = out.odd.parameters[p], &b = out.even.parameters[p];
    ParameterComparison c;
    c.name = a.name;
    c.odd = a.value;
    c.even = b.value;
    c.odd_sigma = a.sigma;
    c.even_sigma = b.sigma;
    c.difference = a.value - b.value;
    c.combined_sigma = std::hypot(a.sigma, b.sigma);
    c.fixed = a.fixed;
    if (!c.fixed && c.combined_sigma > 0) {
      c.ratio = std::abs(c.difference) / c.combined_sigma;
      sum += c.ratio * c.ratio;
      ++free;
    }
    out.parameters.push_back(c);
  }
  out.ratio_rms = free ? std::sqrt(sum / free) : 0.0;
  compare_halvings(views, board, settings, out);
  out.ok = true;
  return out;
}

}  // namespace naneye::recon
