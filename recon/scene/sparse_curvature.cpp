// The sparse path's curvature model (SparseSettings::curvature_radius_px). An affine warp over an LK
// window cannot follow a curved surface. The right image's place of left pixel offset q is
// F(q, w(q)), F the exact model's map at inverse depth w (sparse.hpp, WideCandidate); the LK's
// template shape is F(q, w0) and its affine takes what is linear in q, so to second order what is
// left is d(q) = 1/2 q^T C q with the vector coefficients
//   C_ab = H_ab F_w + F_ww g_a g_b + F_wq,a g_b + F_wq,b g_a
// (w(q) = w0 + g^T q + 1/2 q^T H q; F_w, F_ww, F_wq its derivatives): the surface's curvature, and
// on a steep one the curve's own bending. That biases the match by sum_m
// LkResult::curvature_gain[m] c_m, ~ (window radius)^2: on the simulator's height field a 13 x 13
// window's error/sigma had mean -0.6, a sphere's 17 x 17 +0.8, a tube's 21 x 21 -1.0
// (bench_scene --refusals). The nested tests (sparse_wide.cpp) refused such windows only where the
// bias showed against the noise, and let through what hid in it.
// g and H are the neighbourhood's: a weighted least-squares quadric w(q) = a + g^T q + 1/2 q^T H q
// through the other features' narrow matches within the radius (weights 1 / sigma_w^2, sigma_w =
// the depth sigma / Z^2), its covariance (X^T W X)^-1 scaled by the fit's reduced chi-square where
// that is above 1 (a surface the quadric does not follow over the neighbourhood says so in its
// residual). The feature's own match is left out of its fit, so its noise and its model's are
// independent: every window's match is corrected by its bias and its covariance takes the model's
// share, J Cov J^T.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::recon::scene {
namespace {

// The quadric's six parameters need a few more neighbours to say anything of its residual.
constexpr int kMinNeighbours = 10;

}  // namespace

void SparseReconstructor::fit_curvature(SparseResult& out) {
  for (WideCandidate& wc : wide_) wc.has_curvature = wc.curvature_misfit = false;
  if (!(s_.curvature_radius_px > 0)) return;
  std::fill(cell_point_.begin(), cell_point_.end(), -1);
  for (std::size_t k = 0; k < out.points.size(); ++k)
    if (out.points[k].valid()) cell_point_[point_cell(out.points[k].left_px)] = static_cast<int>(k);
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  for (std::size_t k = 0; k < out.points.size(); ++k) {
    const ScenePoint& p = out.points[k];
    if (!p.valid()) continue;
    Mat6 N = Mat6::Zero();
    Vec6 b = Vec6::Zero();
    double ww = 0;
    int count = 0;
    for_each_near(out, p.left_px, s_.curvature_radius_px, [&](std::size_t j) {
      if (j == k) return;
      const ScenePoint& q = out.points[j];
      const Eigen::Vector2d dq = q.left_px - p.left_px;
      const double z = q.X.z(), w = 1.0 / z, sw = q.depth_sigma_mm / (z * z), weight = 1.0 / (sw * sw);
      Vec6 row;
      row << 1, dq.x(), dq.y(), 0.5 * dq.x() * dq.x(), dq.x() * dq.y(), 0.5 * dq.y() * dq.y();
      N.selfadjointView<Eigen::Lower>().rankUpdate(row, weight);
      b += weight * w * row;
      ww += weight * w * w;
      ++count;
    });
    if (count < kMinNeighbours) continue;
    N.triangularView<Eigen::Upper>() = N.transpose();
    const Eigen::LDLT<Mat6> ldlt(N);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) continue;
    const Vec6 theta = ldlt.solve(b);
    const double chi2 = std::max(0.0, ww - b.dot(theta)), nu = count - 6;
    WideCandidate& wc = wide_[k];
    // A neighbourhood the quadric does not follow (the height preset's waves within the radius)
    // leaves the model's own bias unknown: no wider window there (choose_wide).
    if (chi2 > nu * chi2_upper_ratio(nu, wide_z_)) {
      wc.curvature_misfit = true;
      continue;
    }
    const Mat6 cov = ldlt.solve(Mat6::Identity()) * std::max(1.0, chi2 / nu);
    set_curvature_model(wc, theta, cov);
  }
}

void SparseReconstructor::set_curvature_model(WideCandidate& wc, const Eigen::Matrix<double, 6, 1>& theta,
                                              const Eigen::Matrix<double, 6, 6>& cov) const {
  const double gx = theta(1), gy = theta(2);
  const Eigen::Vector2d &Fw = wc.dpdw, &Fww = wc.d2pdw2;
  const Eigen::Vector2d Fq0 = wc.d2pdwdq.col(0), Fq1 = wc.d2pdwdq.col(1);
  wc.c.col(0) = theta(3) * Fw + Fww * gx * gx + 2 * Fq0 * gx;
  wc.c.col(1) = theta(4) * Fw + Fww * gx * gy + Fq0 * gy + Fq1 * gx;
  wc.c.col(2) = theta(5) * Fw + Fww * gy * gy + 2 * Fq1 * gy;
  // Their derivatives by (g_x, g_y, h_xx, h_xy, h_yy).
  for (auto& d : wc.dc_dtheta) d.setZero();
  wc.dc_dtheta[0].col(0) = 2 * Fww * gx + 2 * Fq0;
  wc.dc_dtheta[0].col(2) = Fw;
  wc.dc_dtheta[1].col(0) = Fww * gy + Fq1;
  wc.dc_dtheta[1].col(1) = Fww * gx + Fq0;
  wc.dc_dtheta[1].col(3) = Fw;
  wc.dc_dtheta[2].col(1) = 2 * Fww * gy + 2 * Fq1;
  wc.dc_dtheta[2].col(4) = Fw;
  // The affine acts on the template shape's places F(q, w0), not on q: the depth gradient's linear
  // part, F_w g^T q = F_w g^T (dF/dq)^-1 (F(q) - F(0)) less F's own second order, leaves
  // -F_w g^T (dF/dq)^-1 F_qq in d. Without it the tube's 21 x 21 bias was predicted 2x (slope 0.2
  // of the error on the prediction; 0.7 with it), most near the image edge where F bends.
  const Eigen::Matrix<double, 2, 3> k = wc.dpdq.inverse() * wc.d2pdq2;
  for (int m = 0; m < 3; ++m) {
    auto& d = wc.dc_dtheta[static_cast<std::size_t>(m)];
    wc.c.col(m) -= Fw * (gx * k(0, m) + gy * k(1, m));
    d.col(0) -= Fw * k(0, m);
    d.col(1) -= Fw * k(1, m);
  }
  wc.theta_cov = cov.bottomRightCorner<5, 5>();
  // A curvature the neighbourhood cannot tell from none is not corrected: its correction would add
  // the model's noise (on a plane ~0.2 sigma of a 21 x 21 match at 28 px) for a bias under ~2.6 of
  // that; the shift tests guard what is left, as they do without a model.
  if (!wc.narrow_has_gain) return;  // the test below needs the narrow window's
  Eigen::Matrix<double, 2, 5> J;
  const Eigen::Vector2d e = wc.dpdw.normalized();
  const double be = e.dot(curvature_bias(wc, wc.narrow_gain, &J));
  const Eigen::Matrix<double, 5, 1> a = J.transpose() * e;
  wc.has_curvature = be * be > wide_chi1_ * a.dot(wc.theta_cov * a);
}

void SparseReconstructor::displacement_derivatives(const Feature& f, double w, WideCandidate& wc) const {
  const auto F = [&](int du, int dv, double wi) {
    const std::size_t i = static_cast<std::size_t>(f.v + dv) * luma_.width + f.u + du;
    const Eigen::Vector3d ray(rays_[2 * i], rays_[2 * i + 1], 1.0);
    return rig_.right.project(rig_.R * ray / wi + rig_.T);
  };
  // Central differences: 1 % of w (a step of ~0.1-1 px along the curve, short against its bending)
  // and the neighbouring pixels (inside the domain: the narrow window is).
  const double hw = 0.01 * w;
  const auto Fw = [&](int du, int dv) -> Eigen::Vector2d {
    return (F(du, dv, w + hw) - F(du, dv, w - hw)) / (2 * hw);
  };
  const Eigen::Vector2d f0 = F(0, 0, w), fp = F(0, 0, w + hw), fm = F(0, 0, w - hw);
  wc.dpdw = (fp - fm) / (2 * hw);
  wc.d2pdw2 = (fp - 2 * f0 + fm) / (hw * hw);
  wc.d2pdwdq.col(0) = 0.5 * (Fw(1, 0) - Fw(-1, 0));
  wc.d2pdwdq.col(1) = 0.5 * (Fw(0, 1) - Fw(0, -1));
  const Eigen::Vector2d fx1 = F(1, 0, w), fx0 = F(-1, 0, w), fy1 = F(0, 1, w), fy0 = F(0, -1, w);
  wc.dpdq.col(0) = 0.5 * (fx1 - fx0);
  wc.dpdq.col(1) = 0.5 * (fy1 - fy0);
  wc.d2pdq2.col(0) = fx1 - 2 * f0 + fx0;
  wc.d2pdq2.col(1) = 0.25 * (F(1, 1, w) - F(1, -1, w) - F(-1, 1, w) + F(-1, -1, w));
  wc.d2pdq2.col(2) = fy1 - 2 * f0 + fy0;
}

Eigen::Vector2d SparseReconstructor::curvature_bias(const WideCandidate& wc, const CurvatureGain& gain,
                                                    Eigen::Matrix<double, 2, 5>* jacobian) {
  Eigen::Vector2d bias = Eigen::Vector2d::Zero();
  if (jacobian) jacobian->setZero();
  for (std::size_t m = 0; m < 3; ++m) {
    bias += gain[m] * wc.c.col(static_cast<Eigen::Index>(m));
    if (jacobian) *jacobian += gain[m] * wc.dc_dtheta[m];
  }
  return bias;
}

bool SparseReconstructor::correct_for_curvature(const WideCandidate& wc, const Eigen::Vector2d& left_px,
                                                const CurvatureGain& gain, Eigen::Vector2d& right_px,
                                                Eigen::Matrix2d& cov, Eigen::Vector3d& X,
                                                double& depth_sigma_mm) const {
  Eigen::Matrix<double, 2, 5> J;
  right_px -= curvature_bias(wc, gain, &J);
  cov += J * wc.theta_cov * J.transpose();
  return triangulate_match(left_px, right_px, cov, X, depth_sigma_mm);
}

}  // namespace naneye::recon::scene
