// The sub-pixel refinement of a whole grid (CornerDetector::refine_all): pass 1 from the coarse or
// previous grid, pass 2 with the edges of the pass-1 grid, then the acceptance of every fit
// (docs/corners.md).
#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <span>

#include "naneye/base/median.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/refine.hpp"
#include "naneye/recon/corners/sine_fit.hpp"

namespace naneye::recon {

namespace {
struct Grid {
  const std::array<Eigen::Vector2d, kMaxCorners>& p;
  int rows, cols;
  const Eigen::Vector2d& at(int r, int c) const { return p[static_cast<std::size_t>(r * cols + c)]; }
  // Grid steps along the row (to the next column) and along the column, one-sided at the border.
  void steps(int r, int c, Eigen::Vector2d& dc, Eigen::Vector2d& dr) const {
    const int c0 = std::max(c - 1, 0), c1 = std::min(c + 1, cols - 1);
    const int r0 = std::max(r - 1, 0), r1 = std::min(r + 1, rows - 1);
    dc = (at(r, c1) - at(r, c0)) / (c1 - c0);
    dr = (at(r1, c) - at(r0, c)) / (r1 - r0);
  }
};
}  // namespace

namespace {
// Sum over lags of the squared correlation of noise filtered by the 3 x 3 binomial ([1 2 1] / 4 per
// axis: correlations 1, 2/3, 1/6 at lags 0, 1, 2, so 1 + 2 (4/9 + 1/36) = 1.944 per axis): a window
// of n filtered pixels has the residual-variance spread of n / 3.78 independent ones.
constexpr double kBayerNoiseCorrelation = 1.9444444444444444 * 1.9444444444444444;
}  // namespace

double CornerDetector::residual_bound(const SaddleFit& fit, double radius, double misfit) const {
  const double var_n = noise_.variance(fit.shading.valid ? fit.shading.a : 0.0);
  const double side = 2.0 * radius + 1.0;
  double nu = (fit.weight > 0 ? fit.weight : side * side) - (fit.harmonic ? 13.0 : 9.0);
  if (bayer_) nu /= kBayerNoiseCorrelation;
  nu = std::max(nu, 4.0);
  const double m = misfit * fit.contrast;
  return var_n * chi2_upper_ratio(nu, z_reject_) + m * m;
}

double CornerDetector::position_se(const SaddleFit& fit) const {
  // Least squares' position variance for the frame's noise at the corner's level; the Bayer
  // luminance's neighbours are correlated (the binomial), which widens it like the residual's spread.
  const double var_n = noise_.variance(fit.shading.valid ? fit.shading.a : 0.0);
  return std::sqrt(var_n * fit.position_var_per_noise * (bayer_ ? kBayerNoiseCorrelation : 1.0));
}

CornerDetector::BlurVerdict CornerDetector::blur_verdict(const SaddleFit& fit, double radius) const {
  // The harmonic model has no blur to fit and no window to outgrow: it holds the corner or not.
  if (fit.harmonic) {
    return position_se(fit) <= settings_.max_position_se_px ? BlurVerdict::held : BlurVerdict::refused;
  }
  if (fit.sigma < settings_.min_sigma_px) return BlurVerdict::refused;
  if (fit.sigma <= settings_.max_sigma_per_radius * radius) return BlurVerdict::held;
  // A blur beyond the window's +-2.5 sigma: the window is as large as the grid lets it be (a far
  // board's squares of 4-6 px under a ~1 px blur), so the erf's tails meet the next lines'. The
  // corner is still measured when the fit holds it to the noise; it is flagged poor either way,
  // the model (one X-junction) not being all the window shows.
  return position_se(fit) <= settings_.max_position_se_px ? BlurVerdict::poor : BlurVerdict::refused;
}

bool CornerDetector::fit_acceptable(const SaddleFit& fit, double radius) const {
  return fit.rms * fit.rms <= residual_bound(fit, radius, settings_.model_misfit) &&
         2.0 * fit.contrast >= settings_.min_contrast_snr * std::sqrt(noise_.variance(fit.shading.a)) &&
         blur_verdict(fit, radius) != BlurVerdict::refused;
}

double CornerDetector::fit_radius(double spacing) const {
  // The window must not reach the neighbouring corners' edges (blur included).
  return std::clamp(settings_.window_fraction * spacing, settings_.min_radius, settings_.max_radius);
}

bool CornerDetector::fit_corner(const SaddleInit& init, const EdgeDirections* edges, double radius,
                                double tolerance_px, SaddleFit& fit, std::uint8_t& flags) {
  const LumaView v = luma_view();
  FastFitScratch& w = work_.front();
  auto run = [&](const SaddleInit& s, double rad, SaddleFit& f) {
    return fit_saddle_fast(v, camera_, *map_, s, edges, rad, 50, tolerance_px, w, f);
  };
  bool ok = run(init, radius, fit);
  while (!ok && radius > settings_.min_radius) {
    const int half = static_cast<int>(std::ceil(radius)) + 1;
    const int cx = static_cast<int>(std::lround(init.px.x())),
              cy = static_cast<int>(std::lround(init.px.y()));
    const bool at_edge =
        cx - half < 0 || cx + half >= col_end_ || cy - half < row_begin_ || cy + half >= row_end_;
    if (!at_edge) break;
    radius = std::max(radius - 1.0, settings_.min_radius);
    flags |= kCornerNearEdge;
    ok = run(init, radius, fit);
  }
  // A start far from the optimum can let the blur collapse (the erf turns into a step and its
  // gradient vanishes): retry once from a wide blur before giving up on the corner.
  const bool poor = ok && (!fit_acceptable(fit, radius) || fit.sigma < 0.1);
  if (!ok || poor) {
    SaddleInit wide = init;
    wide.sigma = 1.2;
    wide.shading.valid = false;  // solve the linear terms afresh too
    SaddleFit retry;
    if (run(wide, radius, retry) && (!ok || retry.rms < fit.rms)) {
      fit = retry;
      ok = true;
    }
  }
  return ok;
}

bool CornerDetector::prefer_harmonic(const Eigen::Vector2d& px, const Eigen::Vector2d& dc,
                                     const Eigen::Vector2d& dr, int row, int col, int rows, int cols,
                                     double tolerance_px, SaddleFit& fit, double& radius) {
  const double spacing = std::min(dc.norm(), dr.norm());
  if (!(spacing <= settings_.harmonic_max_spacing_px)) return false;
  // The board's squares reach one step beyond its outer inner corners: on that side the window
  // keeps half a step clear of where they end (the margin's step, blurred, is no checkerboard).
  SineInit init;
  init.px = px;
  init.step_col = dc;
  init.step_row = dr;
  init.extent_col = init.extent_row = settings_.harmonic_window_steps;
  init.border_extent = std::min(0.5, settings_.harmonic_window_steps);
  init.border_col_lo = col == 0;
  init.border_col_hi = col == cols - 1;
  init.border_row_lo = row == 0;
  init.border_row_hi = row == rows - 1;
  SaddleFit h;
  const bool okh = fit_sine_corner(luma_view(), camera_, *map_, init, 50, tolerance_px, work_.front(), h);
  // The radius of a square window of as many pixels (the rejection report's figure).
  const double r = std::max(0.5 * (std::sqrt(h.weight) - 1.0), settings_.min_radius);
  if (!okh || !fit_acceptable(h, r)) {
    return false;
  }
  if (fit.converged && fit_acceptable(fit, radius) && position_se(fit) <= position_se(h)) return false;
  fit = h;
  radius = r;
  harmonic_used_ = true;
  return true;
}

void CornerDetector::grid_edges(const std::array<Eigen::Vector2d, kMaxCorners>& px, int rows, int cols) {
  // The board's edges through a corner are the grid lines through its neighbours, straight on the
  // undistorted plane: their directions come from the grid itself, more precisely than a 7 px
  // window can fit them (a 0.02 px corner error over two spacings is ~1e-3 rad).
  std::array<Eigen::Vector2d, kMaxCorners> xn;
  std::array<bool, kMaxCorners> ok{};
  for (int i = 0; i < rows * cols; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Undistorted u = camera_.undistort(px[k]);
    ok[k] = u.ok();
    xn[k] = u.normalized;
  }
  auto at = [&](int r, int c) { return static_cast<std::size_t>(r * cols + c); };
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int c0 = std::max(c - 1, 0), c1 = std::min(c + 1, cols - 1);
      const int r0 = std::max(r - 1, 0), r1 = std::min(r + 1, rows - 1);
      EdgeDirections& e = edges_[at(r, c)];
      e.row_px = px[at(r, c1)] - px[at(r, c0)];
      e.col_px = px[at(r1, c)] - px[at(r0, c)];
      e.normalized_ok = ok[at(r, c0)] && ok[at(r, c1)] && ok[at(r0, c)] && ok[at(r1, c)];
      e.row_n = xn[at(r, c1)] - xn[at(r, c0)];
      e.col_n = xn[at(r1, c)] - xn[at(r0, c)];
      // The grid's cell at this corner: the next row line lies area / |row step| away along the row
      // edge's normal, the next column line area / |column step| along the other (the spacing for a
      // square grid, less for a skewed one).
      const Eigen::Vector2d dc = e.row_px / (c1 - c0), dr = e.col_px / (r1 - r0);
      const double area = std::abs(dc.x() * dr.y() - dc.y() * dr.x());
      e.row_line_px = dc.norm() > 0 ? area / dc.norm() : 0.0;
      e.col_line_px = dr.norm() > 0 ? area / dr.norm() : 0.0;
    }
  }
}

namespace {
// Tracking: the motion of the corners fitted in pass 1 (`fitted`) as one affine map of the previous
// positions, applied to the others (their blur from the nearest fitted corner is not needed: pass 2
// starts from the previous blur). False when the motion is not affine within 0.3 px: the board
// moved too much or a fit locked onto the wrong corner; a full search follows.
bool affine_motion(const std::array<Eigen::Vector2d, kMaxCorners>& prev,
                   const std::array<bool, kMaxCorners>& fitted, std::size_t n,
                   std::array<Eigen::Vector2d, kMaxCorners>& now) {
  Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> Atb = Eigen::Matrix<double, 3, 2>::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (!fitted[i]) continue;
    const Eigen::Vector3d a(prev[i].x(), prev[i].y(), 1.0);
    AtA += a * a.transpose();
    Atb += a * now[i].transpose();
  }
  const Eigen::Matrix<double, 3, 2> M = AtA.ldlt().solve(Atb);
  if (!M.allFinite()) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p = M.transpose() * Eigen::Vector3d(prev[i].x(), prev[i].y(), 1.0);
    if (fitted[i] && (p - now[i]).norm() > 0.3) return false;
    if (!fitted[i]) now[i] = p;
  }
  return true;
}
}  // namespace

bool CornerDetector::refine_all(CornerResult& out, bool from_previous) {
  harmonic_used_ = false;
  constexpr double kHalfPi = 1.57079632679489661923;
  const std::size_t n = static_cast<std::size_t>(out.count);
  std::array<Eigen::Vector2d, kMaxCorners> start, first;
  std::array<SaddleFit, kMaxCorners> fits;
  std::array<std::uint8_t, kMaxCorners> flags{};
  std::array<double, kMaxCorners> radii{};
  for (std::size_t i = 0; i < n; ++i) start[i] = out.corners[i].px;
  // Pass 1: from the coarse (or previous) grid, with windows sized by its spacing. From a coarse
  // grid all 11 parameters are fitted at every corner. From the previous frame's grid, only a few
  // corners are fitted (edges from that grid, see grid_edges: corner, blur and shading only) and an
  // affine motion through them moves the others: pass 2 only needs its windows centred within a few
  // hundredths of a pixel of where the full search would centre them.
  const Grid g0{start, out.rows, out.cols};
  if (from_previous) grid_edges(start, out.rows, out.cols);
  const int R = out.rows - 1, C = out.cols - 1;
  auto sparse = [&](int r, int c) {
    return (r == 0 || r == R || r == R / 2) && (c == 0 || c == C || c == C / 2);
  };
  std::array<bool, kMaxCorners> fitted{};
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      const auto i = static_cast<std::size_t>(r * out.cols + c);
      if (from_previous && !sparse(r, c)) continue;
      const Corner& k = out.corners[i];
      Eigen::Vector2d dc, dr;
      g0.steps(r, c, dc, dr);
      SaddleInit init;
      init.px = start[i];
      init.theta1 = std::atan2(dc.y(), dc.x()) + kHalfPi;  // normal of the edge along the row
      init.theta2 = std::atan2(dr.y(), dr.x()) + kHalfPi;  // normal of the edge along the column
      init.sigma = from_previous && k.sigma_px > 0 ? k.sigma_px : 0.8;
      if (from_previous) {
        init.shading = k.shading;
        init.shading_at = k.px;
      }
      // Pass 1 only has to land within a few hundredths of a pixel: a small window is enough.
      const double r1 = std::min(fit_radius(std::min(dc.norm(), dr.norm())), settings_.first_pass_radius);
      // A far board's harmonic fit, when accepted, lands it as well (pass 2 compares the two fits).
      double rh = r1;
      fits[i] = SaddleFit{};
      if (!prefer_harmonic(start[i], dc, dr, r, c, out.rows, out.cols, 1e-2, fits[i], rh) &&
          !fit_corner(init, from_previous ? &edges_[i] : nullptr, r1, 1e-2, fits[i], flags[i])) {
        failure_ = CornerFailure::fit_failed;
        return false;
      }
      first[i] = fits[i].px;
      fitted[i] = true;
    }
  }
  if (from_previous && !affine_motion(start, fitted, n, first)) {
    failure_ = CornerFailure::track_moved;
    return false;
  }
  // Pass 2: the window that the fitted grid calls for, centred on the fitted corner, so that the
  // result does not depend on where the fit started (tracking and full search must agree), with the
  // edges of the pass-1 grid; it starts at the pass-1 optimum and converges in a few iterations.
  const Grid g1{first, out.rows, out.cols};
  grid_edges(first, out.rows, out.cols);
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      const auto i = static_cast<std::size_t>(r * out.cols + c);
      Eigen::Vector2d dc, dr;
      g1.steps(r, c, dc, dr);
      const double radius = fit_radius(std::min(dc.norm(), dr.norm()));
      const Corner& k = out.corners[i];
      const double sigma =
          fitted[i] && fits[i].sigma > 0 ? fits[i].sigma : (k.sigma_px > 0 ? k.sigma_px : 0.8);
      SaddleInit again{first[i], fits[i].theta1, fits[i].theta2, sigma};
      if (fitted[i]) {
        again.shading = fits[i].shading;
        again.shading_at = fits[i].px;
      } else {
        again.shading = k.shading;  // the previous frame's (tracking)
        again.shading_at = k.px;
      }
      flags[i] = 0;
      const bool ok = fit_corner(again, &edges_[i], radius, 1e-3, fits[i], flags[i]);
      radii[i] = radius;
      if (prefer_harmonic(first[i], dc, dr, r, c, out.rows, out.cols, 1e-3, fits[i], radii[i])) continue;
      if (!ok) {
        failure_ = CornerFailure::fit_failed;
        return false;
      }
      // The grid's edge directions hold when the pass-1 corners are right to a few hundredths of a
      // pixel; a close board (sharp edges over few pixels) can miss that and leave the fixed-edge
      // fit poor: then free the edges (11 parameters) and keep the better fit.
      if (!fit_acceptable(fits[i], radius)) {
        SaddleFit free_fit;
        std::uint8_t free_flags = 0;
        if (fit_corner(again, nullptr, radius, 1e-3, free_fit, free_flags) && free_fit.rms < fits[i].rms) {
          fits[i] = free_fit;
          flags[i] = free_flags;
        }
      }
    }
  }
  // The model's misfit is the imaging chain's (JPEG blocks and ringing, a PSF that is no Gaussian)
  // and alike at every corner of a frame: measured on the frame's own corners (their median share of
  // |b| beyond the noise), a corner is refused when its misfit exceeds twice that, and never below
  // model_misfit nor above twice it. On OpenCV's photographs the median is 6-13 % and no corner
  // exceeds 1.7x its frame's median; on the simulator the median is ~1-2 %, so model_misfit holds.
  // The poor flag follows the frame the same way (CornerSettings::poor_per_median).
  std::array<double, kMaxCorners> misfit{};
  for (std::size_t i = 0; i < n; ++i) {
    const double excess = fits[i].rms * fits[i].rms - residual_bound(fits[i], radii[i], 0.0);
    misfit[i] = std::sqrt(std::max(excess, 0.0)) / std::max(fits[i].contrast, 1e-9);
  }
  const double median_misfit = base::upper_median(std::span(misfit).first(n));
  const double frame_misfit =
      std::clamp(2.0 * median_misfit, settings_.model_misfit, 2.0 * settings_.model_misfit);
  const double poor_misfit = std::max(settings_.poor_misfit, settings_.poor_per_median * median_misfit);
  // A border corner's outer squares may end within its window: cut by the print (OpenCV's sample
  // board's outer columns are half squares), the image edge or the fold, so the window holds the
  // margin's edge, which the model has not. Where such a corner's fit is refused, smaller windows,
  // 1 px at a time, until one holds (on that set reduced to squares of 6-11 px every board was
  // refused at a border corner with windows of 0.55 of the spacing).
  for (std::size_t i = 0; i < n; ++i) {
    const int r = static_cast<int>(i) / out.cols, c = static_cast<int>(i) % out.cols;
    const bool border = r == 0 || c == 0 || r == out.rows - 1 || c == out.cols - 1;
    auto holds = [&](const SaddleFit& f, double rad) {
      return f.rms * f.rms <= residual_bound(f, rad, frame_misfit) &&
             blur_verdict(f, rad) != BlurVerdict::refused;
    };
    if (!border || fits[i].harmonic || holds(fits[i], radii[i])) continue;
    SaddleInit again{fits[i].px, fits[i].theta1, fits[i].theta2, fits[i].sigma > 0 ? fits[i].sigma : 0.8};
    again.shading = fits[i].shading;
    again.shading_at = fits[i].px;
    for (double rad = radii[i] - 1.0; rad >= settings_.min_radius; rad -= 1.0) {
      SaddleFit small;
      std::uint8_t small_flags = 0;
      if (fit_corner(again, &edges_[i], rad, 1e-3, small, small_flags) && holds(small, rad)) {
        fits[i] = small;
        flags[i] = small_flags;
        radii[i] = rad;
        break;
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const SaddleFit& fit = fits[i];
    const double var_n = noise_.variance(fit.shading.a);
    rejection_ = CornerRejection{
        static_cast<int>(i), fit.rms,          std::sqrt(residual_bound(fit, radii[i], frame_misfit)),
        2.0 * fit.contrast,  std::sqrt(var_n), fit.shading.a,
        fit.sigma,           radii[i],         position_se(fit)};
    if (2.0 * fit.contrast < settings_.min_contrast_snr * std::sqrt(var_n)) {
      failure_ = CornerFailure::low_contrast;
      return false;
    }
    const bool residual_ok = fit.rms * fit.rms <= residual_bound(fit, radii[i], frame_misfit);
    const BlurVerdict blur = blur_verdict(fit, radii[i]);
    if (!residual_ok || blur == BlurVerdict::refused) {
      failure_ = CornerFailure::fit_rejected;
      return false;
    }
    // A corner its window does not hold to the noise (least squares' standard error beyond
    // max_position_se_px) is returned flagged: on the simulator's conditions the errors run ~1.4-1.9x
    // that figure (pattern noise the model of independent pixels leaves out), so such a corner may
    // be several tenths of a pixel off (seen: the border columns of boards tilted 55-60 degrees,
    // 0.2-0.38 px off, standard errors 0.10-0.36 px).
    if (blur == BlurVerdict::poor || position_se(fit) > settings_.max_position_se_px) {
      flags[i] |= kCornerFitPoor;
    }
    if (fit.rms * fit.rms > residual_bound(fit, radii[i], poor_misfit)) flags[i] |= kCornerFitPoor;
    // Whites clipped so far that the mean of white and black lies beyond the clip: the edges' midpoints,
    // which place the corner, were not imaged but extrapolated from the profile's dark half (seen
    // 0.15-0.35 px off on boards at 36-50 mm exposed for 70 mm, against 0.03 px for the others).
    if (fit.shading.a >= kClipDn) flags[i] |= kCornerFitPoor;
    if (!fit.undistorted || !camera_.in_domain(fit.px)) flags[i] |= kCornerBeyondFold;
    Corner& k = out.corners[i];
    k.px = fit.px;
    k.row = static_cast<int>(i) / out.cols;
    k.col = static_cast<int>(i) % out.cols;
    k.flags = flags[i];
    k.sigma_px = fit.sigma;
    k.contrast = 2.0 * fit.contrast;
    k.residual = fit.rms;
    k.position_se_px = position_se(fit);
    k.theta_row = fit.theta1;
    k.theta_col = fit.theta2;
    k.shading = fit.shading;
  }
  return true;
}

}  // namespace naneye::recon
