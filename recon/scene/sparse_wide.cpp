// The sparse path's wider LK window (sparse.hpp, SparseSettings::wide_radius): a wider window
// averages more noise, but the affine warp (the surface's tilt; Baker & Matthews 2004's IC-LK,
// lk_affine.hpp) must hold over all of it. On a curved surface its misfit is a bias the sigma (noise
// only) leaves out: at 13 x 13 instead of 9 x 9 the height preset's rms(err/sigma) went 1.27 -> 2.12.
// So the wider window's match replaces the narrow one's only where the data cannot tell their models
// apart:
// 1. Per feature, its outer ring (the pixels the narrow window lacks) must fit as well as the narrow
//    window: the ring's residual variance over the narrow window's,
//    F = (SSR_ring / E_ring) / (SSR_n / (N_n - 8)), E_ring = N_ring (N_w - 8) / N_w the ring's expected
//    share of the wide fit's N_w - 8 residual degrees of freedom (8 parameters spread evenly), against
//    the F distribution with (E_ring, N_n - 8) degrees of freedom, each divided by Satterthwaite's
//    factor for the noise's correlation (noise_dof_factor; the two sums are over disjoint pixels,
//    independent up to the noise kernel's one-pixel reach), in Paulson's (1942) normal form
//    z = ((1 - c2) F^(1/3) - (1 - c1)) / sqrt(c2 F^(2/3) + c1), c = 2 / (9 nu). This catches a
//    gross misfit in the ring (an occluding edge, another surface).
// 2. Per feature, its shift along the epipolar curve must agree with the narrow one's (Hausman
//    1978): nested estimates on shared pixels, so d = px_w - px_n is not the sum of their noises;
//    linearised, d = sum_k g_k e_k over the residuals, and its covariance is lk_affine's sandwich
//    over g (LkResult::diff_cov_unit; for white noise Sigma_n - Sigma_w, Hausman's form), at the
//    narrow window's residual variance SSR_n / (N_n - 8), the one its sigma uses. Only the component
//    along the curve moves the depth and carries a surface's misfit (a disparity error); across it is
//    noise alone and would dilute the test: H = (e . d)^2 / (e^T V e), chi-square(1) under the model.
//    A feature whose test fails keeps the match just inside, its sigma widened by the disagreement
//    (disagree(): the failure selects the inner matches whose noise was large).
// 3. Pooled over the neighbourhood (wide_pool_radius_px): a curved surface biases the wide windows
//    of neighbouring features alike, by ~0.7 sd of one feature's test on the height preset (mean H
//    1.7 there, 0.9-1.0 on the planes), which one feature's test cannot see. The sum of H over the
//    k features within the radius is chi-square(k) under the model (disjoint noise up to their
//    windows' small overlap): its upper quantile by Wilson-Hilferty,
//    chi2_nu / nu ~ (1 - 2/(9 nu) + z sqrt(2/(9 nu)))^3.
// Measured (docs/scene.md): 13 x 13 everywhere, height rms(err/sigma) 2.12; with tests 1 and 2
// alone, 1.93; with 3, 1.27, the narrow window's own, while the planes keep ~99 % of their wider
// windows (plane-far depth error 0.57 -> 0.41 % mono).
// Nested (SparseSettings::wide_step, 2026-12-07): the window grows ring by ring, and "narrow" in the
// tests above is the step just inside; a point keeps the widest step that passed, with test 3, at
// every narrower step. Against the 9 x 9 window a 21 x 21 fit's misfit hides in the 9 x 9's noise
// (2.3x its sd): the sphere's 21 x 21 points had rms(err/sigma) 2.14 in one step, none pass nested.
// The curvature model (sparse_curvature.cpp, 2026-12-07): tests 2 and 3 are on the shift less the
// share the model predicts for it (the two windows' biases differ), at a variance that adds the
// model's, and the match kept is corrected by its own bias. They run in choose_wide, once every
// feature's narrow match is known (the model is the neighbours'); test 1 in widen.
// One step first (SparseSettings::wide_direct, 2026-12-07, fourteenth session): with the model the
// single step to the widest window holds its sigmas, so every feature first tries it alone (one fit
// where the ladder took three: a plane's features mostly pass), and only those it refuses climb
// the ladder below it, a curvature misfit too (its tests are its neighbours' pools). A refused one
// step's disagreement stays on the point unless the ladder keeps a wider window (docs/scene.md,
// "One step first").
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::recon::scene {

void SparseReconstructor::init_wide() {
  wide_z_ = upper_normal_quantile(s_.wide_false_reject);
  // chi-square(1)'s upper quantile: the square of the normal's two-sided one.
  wide_chi1_ = std::pow(upper_normal_quantile(s_.wide_false_reject / 2), 2);
  wide_kappa_[0] = noise_dof_factor(LkSettings{}.noise_kernel);
  wide_kappa_[1] = noise_dof_factor(LkSettings::binomial3());
  const int wide = std::max(s_.wide_radius, s_.lk.radius), side = 2 * wide + 1;
  for (int r : wide_radii_) ssr_quantile_[static_cast<std::size_t>(r)] = ssr_noise_bound(r);
  for (auto& shape : shape_wide_)
    shape.assign(static_cast<std::size_t>(side * side), Eigen::Vector2d::Zero());
  wide_.reserve(static_cast<std::size_t>(s_.max_features));
  const int cell = s_.features.cell_px;
  const int gw = (rig_.left.width() + cell - 1) / cell, gh = (rig_.left.height() + cell - 1) / cell;
  cell_point_.assign(static_cast<std::size_t>(gw) * gh, -1);
}

void SparseReconstructor::predict_shape(const Feature& f, double w, int rad, int skip,
                                        Eigen::Vector2d* out) const {
  const double z = 1.0 / w;
  const std::size_t np = right_rays_.size() / 3;
  const double *rx = right_rays_.data(), *ry = rx + np, *rz = ry + np;
  const CameraModel& cam = rig_.right;
  // Runs of one row: the window's pixels i0 .. i0 + n - 1 to o[0 .. n - 1].
  const auto run = [&](std::size_t i0, int n, Eigen::Vector2d* o) {
    cam.project_rays_at(rx + i0, ry + i0, rz + i0, z, rig_.T, n, o);
  };
  Eigen::Vector2d c0;
  run(static_cast<std::size_t>(f.v) * luma_.width + f.u, 1, &c0);
  const int side = 2 * rad + 1;
  for (int dr = -rad; dr <= rad; ++dr) {
    const std::size_t row = static_cast<std::size_t>(f.v + dr) * luma_.width + f.u;
    Eigen::Vector2d* o = out + (dr + rad) * side + rad;  // this row's dc = 0
    if (std::abs(dr) > skip) {
      run(row - rad, side, o - rad);
      for (int dc = -rad; dc <= rad; ++dc) o[dc] -= c0;
    } else {  // the ring's two pieces either side of the skipped square
      run(row - rad, rad - skip, o - rad);
      run(row + skip + 1, rad - skip, o + skip + 1);
      for (int dc = skip + 1; dc <= rad; ++dc) {
        o[-dc] -= c0;
        o[dc] -= c0;
      }
    }
  }
}

bool SparseReconstructor::take_fit(const LkResult& fit, const Eigen::Vector2d& left_px, WideStep& st) const {
  if (!fit.converged || !triangulate_match(left_px, fit.px, fit.cov, st.X, st.depth_sigma_mm)) return false;
  st.usable = true;
  st.right_px = fit.px;
  st.cov = fit.cov;
  st.zncc = fit.zncc;
  return true;
}

void SparseReconstructor::widen_steps(const StereoLuma& luma, const Feature& f, double w,
                                      const Eigen::Matrix2d& A0, const LkSettings& lks,
                                      const LkResult& narrow, const Eigen::Vector2d& left_px,
                                      double noise_sigma_dn, std::size_t steps, WideCandidate& wc) {
  LkResult fits[2];  // this step's and the one before, alternately (as shape_wide_)
  const LkResult* inner = &narrow;
  const Eigen::Vector2d* inner_shape = shape_.data();
  for (std::size_t k = 0; k < steps; ++k) {
    Eigen::Vector2d* shape = shape_wide_[k % 2].data();
    LkResult& fit = fits[k % 2];
    WideStep& st = wc.step[k];
    fit = widen(luma, f, w, A0, lks, k, k == 0 ? s_.lk.radius : wide_radii_[k - 1], *inner, inner_shape,
                shape, noise_sigma_dn, st);
    if (!take_fit(fit, left_px, st)) return;
    inner = &fit;
    inner_shape = shape;
  }
}

LkResult SparseReconstructor::widen(const StereoLuma& luma, const Feature& f, double w,
                                    const Eigen::Matrix2d& A0, const LkSettings& lks, std::size_t k, int rn,
                                    const LkResult& narrow, const Eigen::Vector2d* inner_shape,
                                    Eigen::Vector2d* shape, double noise_sigma_dn, WideStep& st) {
  const int rw = wide_radii_[k];
  if (!usable_wide_[k][0][static_cast<std::size_t>(f.v) * luma.width + f.u]) return {};
  const int sn = 2 * rn + 1, sw = 2 * rw + 1;
  for (int dr = -rn; dr <= rn; ++dr)
    for (int dc = -rn; dc <= rn; ++dc)
      shape[static_cast<std::size_t>((dr + rw) * sw + dc + rw)] =
          inner_shape[static_cast<std::size_t>((dr + rn) * sn + dc + rn)];
  predict_shape(f, w, rw, rn, shape);
  LkSettings wl = lks;
  wl.radius = rw;
  wl.inner_radius = rn;
  const LkResult wide =
      refine_affine(luma.left_view(), detector_.gx(), detector_.gy(), f.u, f.v, luma.right_spline_view(),
                    usable_wide_[k][1].data(), narrow.px, A0, shape, wl, &narrow.A);
  // The narrow window's acceptance (at the measured sensor the tube's wider windows failed the ZNCC
  // alone).
  if (!fit_accepted(wide, rw, noise_sigma_dn) || !(narrow.ssr_dn2 > 0)) return {};
  const double nn = sn * sn, nw = sw * sw, e_ring = (nw - nn) * wide.noise_dof / nw, dof_n = narrow.noise_dof;
  if (!(dof_n > 0 && e_ring > 0)) return {};
  // The difference's covariance at the narrow window's residual variance (the wide one's would be
  // inflated by the very misfit the test looks for).
  const Eigen::Matrix2d V = wide.diff_cov_unit * (narrow.ssr_dn2 / dof_n / wide.template_ss_dn2);
  if (!(V.trace() > 0 && V.determinant() > 0)) return {};
  st.tested = true;
  st.d = wide.px - narrow.px;
  st.V = V;
  st.gain = wide.curvature_gain;
  st.has_gain = wide.has_curvature_gain;
  const double kappa = wide_kappa_[luma.bayer ? 1 : 0];
  const double F = (wide.ssr_outer_dn2 / e_ring) / (narrow.ssr_dn2 / dof_n);
  const double c1 = 2 / (9 * e_ring / kappa), c2 = 2 / (9 * dof_n / kappa);
  const double z = ((1 - c2) * std::cbrt(F) - (1 - c1)) / std::sqrt(c2 * std::cbrt(F * F) + c1);
  if (z > wide_z_) return {};
  return wide;
}

void SparseReconstructor::choose_wide(const StereoLuma& luma, double noise_sigma_dn, SparseResult& out) {
  fit_curvature(out);
  if (!direct_first()) {
    for (std::size_t step = 0; step < wide_radii_.size(); ++step) choose_step(out, static_cast<int>(step));
    return;
  }
  choose_step(out, kDirect);
  // The ladder below the widest, where the one step was not kept. A curvature misfit keeps no
  // wider window, but climbs too where a feature that may keep one lies within the pool's radius:
  // its tests are that feature's pool (without them a feature amid misfits pooled with itself
  // alone, and the height field's few that fell back kept 13 x 13 and 17 x 17 windows at
  // rms(err/sigma) 1.6-2.0). Beyond every such radius its fits would enter no test.
  const auto climbs = [&](std::size_t k) { return out.points[k].valid() && !wide_[k].direct_kept; };
  std::fill(cell_point_.begin(), cell_point_.end(), -1);
  for (std::size_t k = 0; k < wide_.size(); ++k)
    if (climbs(k) && !wide_[k].curvature_misfit)
      cell_point_[point_cell(out.points[k].left_px)] = static_cast<int>(k);
  const LkSettings lks = lk_settings(luma.bayer);
  for (std::size_t k = 0; k < wide_.size(); ++k) {
    WideCandidate& wc = wide_[k];
    const ScenePoint& p = out.points[k];
    if (!climbs(k)) continue;
    if (wc.curvature_misfit) {
      bool pooled = false;
      for_each_near(out, p.left_px, s_.wide_pool_radius_px, [&](std::size_t) { pooled = true; });
      if (!pooled) continue;
    }
    const Feature& f = features_[k];
    predict_shape(f, wc.w, s_.lk.radius, -1, shape_.data());
    widen_steps(luma, f, wc.w, wc.A0, lks, wc.narrow, p.left_px, noise_sigma_dn, wide_radii_.size() - 1, wc);
  }
  for (std::size_t step = 0; step + 1 < wide_radii_.size(); ++step) choose_step(out, static_cast<int>(step));
}

void SparseReconstructor::choose_step(SparseResult& out, int k) {
  const auto step_of = [k](WideCandidate& wc) -> WideStep& {
    return k == kDirect ? wc.direct : wc.step[static_cast<std::size_t>(k)];
  };
  const auto inner_gain = [k](const WideCandidate& wc, bool& has) -> const CurvatureGain& {
    if (k <= 0) {
      has = wc.narrow_has_gain;
      return wc.narrow_gain;
    }
    const WideStep& in = wc.step[static_cast<std::size_t>(k - 1)];
    has = in.has_gain;
    return in.gain;
  };
  // Every feature with this step's shift test pools into it, kept or not (the statistic holds
  // under the model either way; more of them see a surface's common bias sooner). The test is on
  // the shift less the curvature model's share of it, at a variance that takes the model's.
  std::fill(cell_point_.begin(), cell_point_.end(), -1);
  bool any = false;
  for (std::size_t j = 0; j < wide_.size(); ++j) {
    WideCandidate& wc = wide_[j];
    WideStep& st = step_of(wc);
    st.hausman = -1;
    if (!st.tested) continue;
    const Eigen::Vector2d e = wc.dpdw.normalized();
    Eigen::Vector2d d = st.d;
    double ve = e.dot(st.V * e);
    bool inner_has = false;
    const CurvatureGain& gain_in = inner_gain(wc, inner_has);
    if (wc.has_curvature && st.has_gain && inner_has) {
      Eigen::Matrix<double, 2, 5> jw, jn;
      d -= curvature_bias(wc, st.gain, &jw) - curvature_bias(wc, gain_in, &jn);
      const Eigen::Matrix<double, 5, 1> a = (jw - jn).transpose() * e;
      ve += a.dot(wc.theta_cov * a);
    }
    st.hausman = e.dot(d) * e.dot(d) / ve;
    st.d_along = e.dot(d);
    cell_point_[point_cell(out.points[j].left_px)] = static_cast<int>(j);
    any = true;
  }
  if (!any) return;
  const int radius = wide_radii_[k == kDirect ? wide_radii_.size() - 1 : static_cast<std::size_t>(k)];
  for (std::size_t j = 0; j < wide_.size(); ++j) {
    ScenePoint& p = out.points[j];
    WideCandidate& wc = wide_[j];
    const WideStep& st = step_of(wc);
    if (!p.valid() || wc.chosen != std::max(k, 0) || !st.usable || wc.curvature_misfit) continue;
    if (st.hausman > wide_chi1_) {
      // The one step's disagreement stands unless the ladder keeps a wider window; the larger of
      // the two where the ladder's own test fails too.
      disagree(wc, p, std::max(std::abs(st.d_along), p.window_disagreement_px));
      continue;
    }
    double sum = 0;
    int count = 0;
    for_each_near(out, p.left_px, s_.wide_pool_radius_px, [&](std::size_t i) {
      sum += step_of(wide_[i]).hausman;
      ++count;
    });
    if (sum > count * chi2_upper_ratio(count, wide_z_)) continue;
    Eigen::Vector2d px = st.right_px;
    Eigen::Matrix2d cov = st.cov;
    Eigen::Vector3d X = st.X;
    double sigma = st.depth_sigma_mm;
    if (wc.has_curvature && st.has_gain && !correct_for_curvature(wc, p.left_px, st.gain, px, cov, X, sigma))
      continue;
    wc.kept_cov = cov;
    p.right_px = px;
    p.X = X;
    p.depth_sigma_mm = sigma;
    p.zncc = st.zncc;
    p.window_radius_px = radius;
    p.window_disagreement_px = 0;
    if (k == kDirect)
      wc.direct_kept = true;
    else
      wc.chosen = k + 1;
  }
}

void SparseReconstructor::disagree(const WideCandidate& wc, ScenePoint& p, double d_along) const {
  // The point keeps the inner match, but its sigma cannot stay the inner fit's noise alone. On a
  // surface the affine fits, a shift beyond the noise says the inner match is the noisy one: it is off by ~d,
  // which the tests select for (the points kept this way had rms(err/sigma) 1.6-2.3 in every bench_scene
  // condition, the others 0.7-1.1). Where the wider window is the biased one, the inner match is as good as
  // its sigma. Its variance along the curve takes d^2: a bound under either reading.
  const Eigen::Vector2d e = wc.dpdw.normalized();
  const Eigen::Matrix2d cov = wc.kept_cov + d_along * d_along * e * e.transpose();
  Eigen::Vector3d X;
  double sigma = 0;
  if (!triangulate_match(p.left_px, p.right_px, cov, X, sigma)) return;
  p.depth_sigma_mm = sigma;
  p.window_disagreement_px = std::abs(d_along);
}

}  // namespace naneye::recon::scene
