// The sparse scene path (sparse.hpp): features -> epipolar ZNCC -> affine LK -> left-right check ->
// niter2 + refinement, with the depth sigma of each match's own precision.
#include "naneye/recon/scene/sparse.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "naneye/base/enum_table.hpp"
#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/recon/scene/bspline.hpp"
#include "round.hpp"

namespace naneye::recon::scene {
namespace {

// Pixels whose ray exists (inside the fold) and that carry image data (RawImageView's ignored
// padding column and edge rows excluded); `rays` (optional, 2 per pixel) gets their normalized rays.
// One undistortion per pixel for all the masks below (it iterates: at 640 x 480 six passes took
// ~10 s of the constructor).
std::vector<std::uint8_t> domain_mask(const CameraModel& cam, const RawImageView& layout, double* rays) {
  const int w = cam.width(), h = cam.height();
  std::vector<std::uint8_t> base(static_cast<std::size_t>(w) * h, 0);
  for (int r = layout.ignore_edge_rows; r < h - layout.ignore_edge_rows; ++r)
    for (int c = 0; c < w - layout.ignore_last_cols; ++c) {
      const Undistorted u = cam.undistort(Eigen::Vector2d(c, r));
      if (!u.ok()) continue;
      const std::size_t i = static_cast<std::size_t>(r) * w + c;
      base[i] = 1;
      if (rays) {
        rays[2 * i] = u.normalized.x();
        rays[2 * i + 1] = u.normalized.y();
      }
    }
  return base;
}

// `base` eroded so that a (2 radius + 1)^2 window around each pixel left fits in it: the square's
// erosion as a row pass then a column pass.
std::vector<std::uint8_t> eroded(const std::vector<std::uint8_t>& base, int w, int h, int radius) {
  std::vector<std::uint8_t> rows(base.size(), 0), out(base.size(), 0);
  for (int r = 0; r < h; ++r)
    for (int c = radius; c < w - radius; ++c) {
      bool ok = true;
      for (int dc = -radius; dc <= radius && ok; ++dc)
        ok = base[static_cast<std::size_t>(r) * w + c + dc] != 0;
      rows[static_cast<std::size_t>(r) * w + c] = ok ? 1 : 0;
    }
  for (int r = radius; r < h - radius; ++r)
    for (int c = 0; c < w; ++c) {
      bool ok = true;
      for (int dr = -radius; dr <= radius && ok; ++dr)
        ok = rows[static_cast<std::size_t>(r + dr) * w + c] != 0;
      out[static_cast<std::size_t>(r) * w + c] = ok ? 1 : 0;
    }
  return out;
}

// The local left -> right raw pixel map at depth 1 / w for a surface facing the camera:
// J_r (d x_r / d x_l) J_l^-1 with J = K_2x2 d(distort)/dx (paper Eq. 5-6). The LK start warp.
Eigen::Matrix2d predicted_affine(const StereoRig& rig, const Eigen::Vector2d& xl, double w) {
  const double z = 1.0 / w;
  const Eigen::Vector3d X(xl.x() * z, xl.y() * z, z);
  const Eigen::Vector3d Xr = rig.R * X + rig.T;
  Eigen::Matrix<double, 2, 3> dproj;
  dproj << 1 / Xr.z(), 0, -Xr.x() / (Xr.z() * Xr.z()), 0, 1 / Xr.z(), -Xr.y() / (Xr.z() * Xr.z());
  const Eigen::Matrix2d dxr = dproj * rig.R.leftCols<2>() * z;
  const Eigen::Vector2d xr = Xr.head<2>() / Xr.z();
  const Eigen::Matrix2d Kl = rig.left.K().topLeftCorner<2, 2>(), Kr = rig.right.K().topLeftCorner<2, 2>();
  const Eigen::Matrix2d Jl = Kl * rig.left.distort_jacobian(xl), Jr = Kr * rig.right.distort_jacobian(xr);
  return Jr * dxr * Jl.inverse();
}
}  // namespace

namespace {
constexpr base::EnumTable<PointStatus, 8> kPointStatusNames{
    {{PointStatus::ok, "ok"},
     {PointStatus::no_candidates, "no_candidates"},
     {PointStatus::weak_match, "weak_match"},
     {PointStatus::ambiguous, "ambiguous"},
     {PointStatus::refinement_failed, "refinement_failed"},
     {PointStatus::left_right_mismatch, "left_right_mismatch"},
     {PointStatus::triangulation_failed, "triangulation_failed"},
     {PointStatus::imprecise, "imprecise"}}};
}  // namespace

const char* to_string(PointStatus s) {
  return base::enum_name(kPointStatusNames, s, "?");
}

SparseReconstructor::SparseReconstructor(const StereoRig& rig, const SparseSettings& s)
    : rig_(rig),
      calib_(CalibrationUncertainty::of(rig)),
      s_(s),
      detector_(rig.left.width(), rig.left.height(), s.features),
      ids_(rig.left.width(), rig.left.height(), s.max_features, s.ids, s.features.cell_px) {
  if (s.lk.radius > kMaxLkRadius || s.wide_radius > kMaxLkRadius)
    throw std::invalid_argument("sparse: lk.radius " + std::to_string(s.lk.radius) + " and wide_radius " +
                                std::to_string(s.wide_radius) + " must be at most " +
                                std::to_string(kMaxLkRadius) + " (the affine LK's widest window)");
  // A 3 x 3 window: one pixel more than the fit's 8 parameters (lk_affine.cpp).
  if (s.lk.radius < 1)
    throw std::invalid_argument("sparse: lk.radius " + std::to_string(s.lk.radius) +
                                " must be at least 1 px");
  if (s.wide_step < 1)
    throw std::invalid_argument("sparse: wide_step " + std::to_string(s.wide_step) +
                                " must be at least 1 px");
  // The quadric's cells are searched within it: a radius past the image would only cost time.
  if (!(s.curvature_radius_px >= 0 && s.curvature_radius_px <= rig.left.width()))
    throw std::invalid_argument("sparse: curvature_radius_px " + std::to_string(s.curvature_radius_px) +
                                " must be within 0 (off) and the image's width");
  R_lr_ = rig_.R;
  T_lr_ = rig_.T;
  R_rl_ = rig_.R.transpose();
  T_rl_ = -R_rl_ * rig_.T;
  const RawImageView layout;
  const std::size_t np = static_cast<std::size_t>(rig_.left.width()) * rig_.left.height();
  rays_.assign(2 * np, 0.0);  // never read outside the domain: features' windows lie inside it
  const std::vector<std::uint8_t> domain[2] = {domain_mask(rig_.left, layout, rays_.data()),
                                               domain_mask(rig_.right, layout, nullptr)};
  right_rays_.assign(3 * np, 0.0);  // planes x, y, z: predict_shape reads them two pixels at a time
  for (std::size_t i = 0; i < np; ++i) {
    const Eigen::Vector3d r = rig_.R * Eigen::Vector3d(rays_[2 * i], rays_[2 * i + 1], 1.0);
    for (int a = 0; a < 3; ++a) right_rays_[a * np + i] = r[a];
  }
  const int w[2] = {rig_.left.width(), rig_.right.width()}, h[2] = {rig_.left.height(), rig_.right.height()};
  const auto usable_mask = [&](int eye, int radius) { return eroded(domain[eye], w[eye], h[eye], radius); };
  usable_[0] = usable_mask(0, s_.lk.radius + 1);
  usable_[1] = usable_mask(1, s_.lk.radius + 1);
  usable_search_[0] = usable_mask(0, s_.search_radius);
  usable_search_[1] = usable_mask(1, s_.search_radius);
  // The noise estimate's 3x3 mask inside the coarse window's domain (a square erosion by r then by 1
  // is one by r + 1).
  noise_mask_ = usable_mask(0, s_.search_radius + 1);
  luma_.width = rig_.left.width();
  luma_.height = rig_.left.height();
  luma_.left.assign(np, 0.f);
  luma_.right.assign(np, 0.f);
  luma_.scratch.assign(np, 0.f);
  luma_.right_spline.assign(np, 0.f);
  ssr_quantile_[static_cast<std::size_t>(s_.lk.radius)] = ssr_noise_bound(s_.lk.radius);
  luma_.left_search.assign(np, 0.f);
  luma_.right_search.assign(np, 0.f);
  features_.reserve(static_cast<std::size_t>(s_.max_features));
  for (int r = s_.lk.radius + s_.wide_step;; r += s_.wide_step) {
    r = std::min(r, s_.wide_radius);
    if (r <= s_.lk.radius) break;
    wide_radii_.push_back(r);
    usable_wide_.push_back({usable_mask(0, r), usable_mask(1, r + 1)});
    if (r == s_.wide_radius) break;
  }
  init_wide();
  id_scratch_.assign(static_cast<std::size_t>(s_.max_features), 0);
  inv_norm_[0].assign(np, 0.f);
  inv_norm_[1].assign(np, 0.f);
  norm_scratch_.assign(2 * static_cast<std::size_t>(luma_.width), 0.0);
  const int side = 2 * s_.lk.radius + 1;
  shape_.assign(static_cast<std::size_t>(side * side), Eigen::Vector2d::Zero());
}

void SparseReconstructor::load_luma(const RawImageView& left, const RawImageView& right) {
  // A scene, not a board: the defect test allows for the texture (raw_to_luminance).
  constexpr bool kTextured = true;
  raw_to_luminance(left, luma_.left.data(), luma_.scratch.data(), kDefectThresholdDn, 0, -1, nullptr,
                   kTextured);
  raw_to_luminance(right, luma_.right.data(), luma_.scratch.data(), kDefectThresholdDn, 0, -1, nullptr,
                   kTextured);
  luma_.bayer = left.layout == PixelLayout::bayer_grbg;
  bspline_coefficients(
      luma_.right_view(),
      {right.width - right.ignore_last_cols, right.ignore_edge_rows, right.height - right.ignore_edge_rows},
      luma_.right_spline.data(), luma_.scratch.data());
  luma_.search_filtered = s_.search_binomial && !luma_.bayer;
  if (luma_.search_filtered) {
    binomial_3x3(luma_.left.data(), luma_.left_search.data(), luma_.width, luma_.height, 0, luma_.height);
    binomial_3x3(luma_.right.data(), luma_.right_search.data(), luma_.width, luma_.height, 0, luma_.height);
  }
}

void SparseReconstructor::reconstruct(const RawImageView& left, const RawImageView& right,
                                      SparseResult& out) {
  load_luma(left, right);
  reconstruct(luma_, out);
}

void SparseReconstructor::reconstruct(const StereoLuma& luma, SparseResult& out) {
  out.points.reserve(static_cast<std::size_t>(s_.max_features));
  out.points.clear();
  out.valid_count = 0;
  const GrayView L = luma.left_view();
  out.noise_sigma_dn = estimate_noise_sigma(L, noise_mask_.data(),
                                            luma.bayer ? LkSettings::binomial3() : LkSettings{}.noise_kernel);
  detector_.detect(L, usable_[0].data(), out.noise_sigma_dn, features_);
  ids_.keep_tracked(L, detector_, usable_[0].data(), out.noise_sigma_dn, features_);
  window_inverse_norms(luma.left_search_view(), s_.search_radius, usable_search_[0].data(),
                       inv_norm_[0].data(), norm_scratch_.data());
  window_inverse_norms(luma.right_search_view(), s_.search_radius, usable_search_[1].data(),
                       inv_norm_[1].data(), norm_scratch_.data());
  // Coarse to fine over the cell grid (SparseSettings::max_points): every 4th cell in both
  // directions, then every 2nd (a lattice of 2 cells' pitch that covers the view), then the rest;
  // strongest first within each, by lambda_min, i.e. by the shift sigma the feature's window allows
  // (features.hpp). Where matching stops early the features left untried are the least precise,
  // not those of the image's bottom rows (raster order, until 2026-12-07: at the measured sensor
  // the sparse depth error 0.517x -> 0.448x the OpenCV path's on the plane, docs/scene.md).
  const int cell = s_.features.cell_px;
  const auto rank = [cell](const Feature& f) {
    const int cx = f.u / cell, cy = f.v / cell;
    if (cx % 4 == 0 && cy % 4 == 0) return 0;
    if (cx % 2 == 0 && cy % 2 == 0) return 1;
    return 2;
  };
  std::sort(features_.begin(), features_.end(), [&](const Feature& a, const Feature& b) {
    const int ra = rank(a), rb = rank(b);
    if (ra != rb) return ra < rb;
    if (a.min_eig != b.min_eig) return a.min_eig > b.min_eig;
    return a.v != b.v ? a.v < b.v : a.u < b.u;
  });
  std::size_t tried = 0;
  wide_.clear();
  for (const Feature& f : features_) {
    if (out.valid_count >= s_.max_points) break;
    ScenePoint p;
    p.left_px = Eigen::Vector2d(f.u, f.v);
    p.right_px.setConstant(std::numeric_limits<double>::quiet_NaN());
    wide_.emplace_back();
    match(luma, f, out.noise_sigma_dn, p, wide_.back());
    // Counted as one of max_points if the narrow or the widest window's depth is precise enough
    // (choose_wide may still refuse the wider one: the final count follows it; where the one step
    // to the widest failed, the ladder it climbs instead may make a few more precise: trimmed below).
    const WideStep* wc = wide_.back().widest();
    out.valid_count +=
        p.valid() && (precise(p.X, p.depth_sigma_mm) || (wc && precise(wc->X, wc->depth_sigma_mm)));
    out.points.push_back(p);
    ++tried;
  }
  choose_wide(luma, out.noise_sigma_dn, out);
  out.valid_count = 0;
  for (std::size_t k = 0; k < tried; ++k) {
    ScenePoint& p = out.points[k];
    if (p.valid() && !precise(p.X, p.depth_sigma_mm)) {
      p.status = PointStatus::imprecise;
      p.X.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
    if (p.valid() && calib_) p.calib_sigma_mm = calib_->depth_sigma_mm(p.X);
    out.valid_count += p.valid();
    // Matching stops at max_points valid: the features after that one as if never tried.
    if (out.valid_count == s_.max_points) tried = k + 1;
  }
  out.points.resize(tried);
  const std::span<std::int64_t> ids(id_scratch_.data(), tried);
  ids_.assign(L, std::span<const Feature>(features_.data(), tried), ids);
  for (std::size_t k = 0; k < tried; ++k) out.points[k].id = ids[k];
}

void SparseReconstructor::match(const StereoLuma& luma, const Feature& f, double noise_sigma_dn,
                                ScenePoint& p, WideCandidate& wc) {
  const GrayView L = luma.left_view(), R = luma.right_view();
  const GrayView Ls = luma.left_search_view(), Rs = luma.right_search_view();
  // The feature is a pixel centre inside the domain: its ray was undistorted once (constructor).
  const std::size_t fi = static_cast<std::size_t>(f.v) * luma.width + f.u;
  const Eigen::Vector2d xl(rays_[2 * fi], rays_[2 * fi + 1]);
  const double w_min = 1.0 / s_.z_max_mm, w_max = 1.0 / s_.z_min_mm;
  sample_epipolar_curve(rig_.right, R_lr_, T_lr_, xl, w_min, w_max, s_.search_step_px, curve_);
  const CurveMatch m = match_along_curve(Ls, f.u, f.v, Rs, usable_search_[1].data(), curve_, s_.search_radius,
                                         inv_norm_[1].data());
  if (!m.found) {
    p.status = PointStatus::no_candidates;
    return;
  }
  p.zncc = m.best;
  if (m.best < s_.min_zncc) {
    p.status = PointStatus::weak_match;
    return;
  }
  if (m.second > -1 && (1 - m.best) > s_.max_ambiguity * (1 - m.second)) {
    p.status = PointStatus::ambiguous;
    return;
  }
  const Eigen::Matrix2d A0 = predicted_affine(rig_, xl, m.w);
  // Where each template pixel lands in the right image for a surface facing the camera at the
  // coarse depth (exact model): near the image edges the map bends within the window.
  predict_shape(f, m.w, s_.lk.radius, -1, shape_.data());
  const LkSettings lks = lk_settings(luma.bayer);
  const LkResult narrow = refine_affine(L, detector_.gx(), detector_.gy(), f.u, f.v, luma.right_spline_view(),
                                        usable_[1].data(), m.px, A0, shape_.data(), lks);
  if (!fit_accepted(narrow, s_.lk.radius, noise_sigma_dn)) {
    p.status = PointStatus::refinement_failed;
    p.zncc = narrow.converged ? narrow.zncc : p.zncc;
    return;
  }
  const LkResult& lk = narrow;
  p.zncc = lk.zncc;
  p.right_px = lk.px;
  p.window_radius_px = s_.lk.radius;
  // Left-right check: the right window, searched along its own curve in the left image, must come
  // back to the feature.
  const Undistorted ur = rig_.right.undistort(lk.px);
  const int ru = round_half_away(lk.px.x()), rv = round_half_away(lk.px.y());
  if (!ur.ok() || !usable_search_[1][static_cast<std::size_t>(rv) * R.width + ru]) {
    p.status = PointStatus::refinement_failed;
    return;
  }
  sample_epipolar_curve(rig_.left, R_rl_, T_rl_, rig_.right.undistort(Eigen::Vector2d(ru, rv)).normalized,
                        w_min, w_max, s_.search_step_px, back_curve_);
  const CurveMatch back = match_along_curve(Rs, ru, rv, Ls, usable_search_[0].data(), back_curve_,
                                            s_.search_radius, inv_norm_[0].data());
  // The back search starts from the rounded right pixel: allow for that rounding.
  const Eigen::Vector2d rounding = Eigen::Vector2d(ru, rv) - lk.px;
  if (!back.found || (back.px - rounding - p.left_px).norm() > s_.lr_tolerance_px) {
    p.status = PointStatus::left_right_mismatch;
    return;
  }
  if (!triangulate_match(p.left_px, lk.px, lk.cov, p.X, p.depth_sigma_mm)) {
    p.status = PointStatus::triangulation_failed;
    return;
  }
  p.status = PointStatus::ok;
  wc.kept_cov = lk.cov;
  displacement_derivatives(f, m.w, wc);  // dpdw also gives the shift tests their direction
  wc.narrow_gain = lk.curvature_gain;
  wc.narrow_has_gain = lk.has_curvature_gain;
  if (!direct_first()) {
    widen_steps(luma, f, m.w, A0, lks, narrow, p.left_px, noise_sigma_dn, wide_radii_.size(), wc);
    return;
  }
  // What choose_wide climbs the ladder from where the one step is refused.
  wc.w = m.w;
  wc.A0 = A0;
  wc.narrow = narrow;
  // The one step from the narrow window to the widest (its ring skips the narrow window's pixels).
  take_fit(widen(luma, f, m.w, A0, lks, wide_radii_.size() - 1, s_.lk.radius, narrow, shape_.data(),
                 shape_wide_[0].data(), noise_sigma_dn, wc.direct),
           p.left_px, wc.direct);
}

LkSettings SparseReconstructor::lk_settings(bool bayer) const {
  LkSettings lks = s_.lk;
  if (bayer) lks.noise_kernel = LkSettings::binomial3();  // raw_to_luminance's filter
  lks.curvature_gain = s_.curvature_radius_px > 0;
  return lks;
}

double SparseReconstructor::ssr_noise_bound(int radius) const {
  if (!(s_.final_noise_false_reject > 0)) return -1;  // 0: the ZNCC alone decides
  const int side = 2 * radius + 1;
  const double nu = side * side - 8;
  return nu * chi2_upper_ratio(nu, upper_normal_quantile(s_.final_noise_false_reject));
}

bool SparseReconstructor::triangulate_match(const Eigen::Vector2d& left_px, const Eigen::Vector2d& right_px,
                                            const Eigen::Matrix2d& cov_px, Eigen::Vector3d& X,
                                            double& depth_sigma_mm) const {
  const Triangulated t = triangulate(rig_, left_px, right_px, TriangulationMethod::refined, 1.0);
  if (!t.ok() || !(t.X.z() > 0)) return false;
  // First-order propagation through the least-squares triangulation, X = (J^T J)^-1 J^T m: the whole
  // match error is the right pixel's (the feature is a pixel centre by definition), with the LK
  // covariance of lk_affine.hpp.
  const Eigen::Matrix<double, 4, 3> J = reprojection_jacobian(rig_, t.X);
  const Eigen::Matrix3d JtJ = J.transpose() * J;
  const Eigen::Matrix<double, 3, 4> G = JtJ.inverse() * J.transpose();
  const Eigen::Matrix<double, 3, 2> Gr = G.rightCols<2>();
  const Eigen::Matrix3d cov = Gr * cov_px * Gr.transpose();
  X = t.X;
  depth_sigma_mm = std::sqrt(cov(2, 2));
  return true;
}

}  // namespace naneye::recon::scene
