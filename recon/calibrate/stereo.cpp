// The joint bundle: Levenberg-Marquardt (Marquardt's diagonal scaling; Madsen, Nielsen & Tingleff,
// "Methods for non-linear least squares problems", 2004, Sec. 3.2 for the damping update) over both
// cameras' intrinsics, the stereo pose and every board pose, on the raw-pixel reprojection error through
// CameraModel. Then the first-order covariance sigma^2 (J^T J)^-1 with sigma^2 = SSR / (n - k)
// (Hartley & Zisserman, 2nd ed., Sec. 5.2.2-5.2.3), its marginals mapped onto the YAML's *_sigma keys.
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "naneye/recon/calibrate/bundle.hpp"
#include "naneye/recon/calibrate/calibrate.hpp"

namespace naneye::recon {
namespace {

using bundle::Layout;
using bundle::State;

constexpr const char* kIntrinsicNames[bundle::kIntrinsics] = {"fx", "fy", "cx", "cy", "k1",
                                                              "k2", "p1", "p2", "k3"};

struct Solution {
  State state;
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  int iterations = 0;
};

bool evaluate_safely(const State& st, const Layout& layout, std::span<const CalibrationView> views,
                     const BoardGeometry& board, const CalibrationSettings& s, Eigen::VectorXd& r,
                     Eigen::MatrixXd* J) {
  try {
    bundle::evaluate(st, layout, views, board, s.image_width, s.image_height, r, J);
  } catch (const std::invalid_argument&) {
    return false;  // a step to a non-positive focal length
  }
  return r.allFinite() && (!J || J->allFinite());
}

// Marquardt's LM: (J^T J + lambda diag(J^T J)) delta = -J^T r, lambda shrunk after a successful step
// and grown after a failed one.
bool levenberg_marquardt(Solution& sol, const Layout& layout, std::span<const CalibrationView> views,
                         const BoardGeometry& board, const CalibrationSettings& s,
                         const std::function<void(const CalibrationProgress&)>& progress) {
  if (!evaluate_safely(sol.state, layout, views, board, s, sol.r, &sol.J)) return false;
  double cost = sol.r.squaredNorm(), lambda = 1e-3;
  const double corners = sol.r.size() / 2.0;
  Eigen::VectorXd r_new;
  for (int it = 0; it < s.max_iterations; ++it) {
    sol.iterations = it + 1;
    const Eigen::MatrixXd A = sol.J.transpose() * sol.J;
    const Eigen::VectorXd g = sol.J.transpose() * sol.r;
    Eigen::VectorXd diag = A.diagonal().cwiseMax(1e-12);
    bool stepped = false, converged = false;
    while (lambda < 1e12) {
      Eigen::MatrixXd Ad = A;
      Ad.diagonal() += lambda * diag;
      const Eigen::VectorXd delta = Ad.ldlt().solve(-g);
      const State trial = bundle::apply(sol.state, layout, delta);
      if (delta.allFinite() && evaluate_safely(trial, layout, views, board, s, r_new, nullptr)) {
        const double c = r_new.squaredNorm();
        if (c < cost) {
          converged = (cost - c) <= 1e-12 * cost || delta.cwiseAbs().maxCoeff() < 1e-12;
          sol.state = trial;
          cost = c;
          lambda = std::max(lambda / 10.0, 1e-12);
          stepped = true;
          break;
        }
      }
      lambda *= 10.0;
    }
    if (progress) progress({sol.iterations, std::sqrt(cost / corners), lambda});
    if (!stepped) break;  // no step lowers the cost: at the minimum (to rounding)
    if (!evaluate_safely(sol.state, layout, views, board, s, sol.r, &sol.J)) return false;
    if (converged) break;
  }
  return evaluate_safely(sol.state, layout, views, board, s, sol.r, &sol.J);
}

// d(om)/d(w) for om = Rodrigues(exp([w]) R) at w = 0, by central differences of a closed-form map
// (not of the cost), so the step can be small.
Eigen::Matrix3d rodrigues_jacobian(const Eigen::Matrix3d& R) {
  Eigen::Matrix3d D;
  const double h = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    w(k) = h;
    D.col(k) = (rodrigues(Eigen::Matrix3d(rodrigues(w) * R)) -
                rodrigues(Eigen::Matrix3d(rodrigues(Eigen::Vector3d(-w)) * R))) /
               (2 * h);
  }
  return D;
}

void fill_result(const Solution& sol, const Layout& layout, std::span<const CalibrationView> views,
                 const CalibrationSettings& s, CalibrationResult& out) {
  const int n = static_cast<int>(sol.r.size()), k = layout.columns;
  const double ssr = sol.r.squaredNorm();
  out.residuals = n;
  out.free_parameters = k;
  out.sigma_px = std::sqrt(ssr / (n - k));
  out.rms_px = std::sqrt(ssr / (n / 2.0));
  out.iterations = sol.iterations;
  const Eigen::MatrixXd A = sol.J.transpose() * sol.J;
  const Eigen::MatrixXd cov = (out.sigma_px * out.sigma_px) * A.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
  auto sd = [&](int c) { return c < 0 ? 0.0 : std::sqrt(std::max(cov(c, c), 0.0)); };

  StereoRig& rig = out.rig;
  rig.left = bundle::camera_of(sol.state.cam[0], s.image_width, s.image_height);
  rig.right = bundle::camera_of(sol.state.cam[1], s.image_width, s.image_height);
  rig.R = sol.state.Rs;
  rig.T = sol.state.Ts;
  for (int eye = 0; eye < 2; ++eye) {
    Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 5, 1> D;
    const auto& idx = layout.index[eye];
    M(0, 0) = sd(idx[0]);
    M(1, 1) = sd(idx[1]);
    M(0, 2) = sd(idx[2]);
    M(1, 2) = sd(idx[3]);
    D << sd(idx[4]), sd(idx[5]), sd(idx[6]), sd(idx[7]), sd(idx[8]);
    (eye == 0 ? rig.sigmas.M1 : rig.sigmas.M2) = M;
    (eye == 0 ? rig.sigmas.D1 : rig.sigmas.D2) = D;
    for (int j = 0; j < bundle::kIntrinsics; ++j)
      out.parameters.push_back({std::string(eye == 0 ? "left." : "right.") + kIntrinsicNames[j],
                                sol.state.cam[eye][j], sd(idx[j]), idx[j] < 0});
  }
  const Eigen::Matrix3d Dom = rodrigues_jacobian(sol.state.Rs);
  const Eigen::Matrix3d cov_om = Dom * cov.block<3, 3>(layout.pose, layout.pose) * Dom.transpose();
  const Eigen::Vector3d om = rodrigues(sol.state.Rs);
  rig.sigmas.om = cov_om.diagonal().cwiseMax(0.0).cwiseSqrt();
  rig.sigmas.T = cov.block<3, 3>(layout.pose + 3, layout.pose + 3).diagonal().cwiseMax(0.0).cwiseSqrt();
  // The full covariance in rig.hpp's order (the marginals above are its diagonal): the bundle's
  // columns mapped by a 24 x k selection, the rotation's local w through d(om)/d(w).
  Eigen::MatrixXd map = Eigen::MatrixXd::Zero(kCalibrationParameters, k);
  for (int eye = 0; eye < 2; ++eye)
    for (int j = 0; j < bundle::kIntrinsics; ++j)
      if (layout.index[eye][j] >= 0)
        map((eye == 0 ? kCalibrationLeft : kCalibrationRight) + j, layout.index[eye][j]) = 1.0;
  map.block<3, 3>(kCalibrationOm, layout.pose) = Dom;
  map.block<3, 3>(kCalibrationT, layout.pose + 3).setIdentity();
  const Eigen::MatrixXd full = map * cov * map.transpose();
  rig.sigmas.covariance = CalibrationCovariance(0.5 * (full + full.transpose()));  // symmetric to the bit
  const char* axes[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a)
    out.parameters.push_back({std::string("om.") + axes[a], om(a), (*rig.sigmas.om)(a)});
  for (int a = 0; a < 3; ++a)
    out.parameters.push_back({std::string("T.") + axes[a], rig.T(a), (*rig.sigmas.T)(a)});

  int row = 0;
  out.worst_px = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    ViewResidual vr;
    vr.view = out.used_views[v];
    double ss[2] = {0, 0};
    for (int eye = 0; eye < 2; ++eye) {
      const auto& corners = eye == 0 ? views[v].left : views[v].right;
      for (std::size_t c = 0; c < corners.size(); ++c, row += 2) {
        const double e = sol.r.segment<2>(row).norm();
        ss[eye] += e * e;
        vr.worst_px = std::max(vr.worst_px, e);
      }
      (eye == 0 ? vr.left_corners : vr.right_corners) = static_cast<int>(corners.size());
    }
    if (vr.left_corners) vr.rms_left_px = std::sqrt(ss[0] / vr.left_corners);
    if (vr.right_corners) vr.rms_right_px = std::sqrt(ss[1] / vr.right_corners);
    vr.rms_px = std::sqrt((ss[0] + ss[1]) / std::max(1, vr.left_corners + vr.right_corners));
    out.worst_px = std::max(out.worst_px, vr.worst_px);
    out.views.push_back(vr);
  }
}

}  // namespace

const ParameterEstimate* CalibrationResult::find(const std::string& name) const {
  for (const auto& p : parameters)
    if (p.name == name) return &p;
  return nullptr;
}

CalibrationResult calibrate_stereo(std::span<const CalibrationView> views, const BoardGeometry& board,
                                   const CalibrationSettings& settings,
                                   const std::function<void(const CalibrationProgress&)>& progress) {
  CalibrationResult out;
  std::vector<CalibrationView> used;
  for (std::size_t v = 0; v < views.size(); ++v) {
    for (const auto* eye : {&views[v].left, &views[v].right})
      for (const BoardCorner& c : *eye)
        if (c.row < 0 || c.row >= board.rows || c.col < 0 || c.col >= board.cols || !c.px.allFinite()) {
          out.message = "view " + std::to_string(v) + ": corner (" + std::to_string(c.row) + ", " +
                        std::to_string(c.col) + ") is not an inner corner of a " +
                        std::to_string(board.rows) + "x" + std::to_string(board.cols) +
                        " board or its pixel is not finite";
          return out;
        }
    if (views[v].left.size() < 4 && views[v].right.size() < 4) {
      out.skipped_views.push_back(static_cast<int>(v));
      continue;
    }
    used.push_back(views[v]);
    out.used_views.push_back(static_cast<int>(v));
  }
  std::string error;
  auto init = bundle::initial_state(used, board, settings, error);
  if (!init) {
    out.message = error;
    return out;
  }
  const Layout layout = bundle::make_layout(settings, static_cast<int>(used.size()));
  const int n = bundle::residual_count(used);
  if (n <= layout.columns) {
    out.message = "too few corners: " + std::to_string(n) + " residuals for " +
                  std::to_string(layout.columns) + " parameters";
    return out;
  }
  Solution sol;
  sol.state = *init;
  {
    Eigen::VectorXd r0;
    if (evaluate_safely(sol.state, layout, used, board, settings, r0, nullptr))
      out.initial_rms_px = std::sqrt(r0.squaredNorm() / (r0.size() / 2.0));
  }
  if (!levenberg_marquardt(sol, layout, used, board, settings, progress)) {
    out.message = "the optimisation diverged (a camera left the model's domain)";
    return out;
  }
  // A rank-deficient J^T J has no covariance: the views do not constrain every parameter.
  const Eigen::MatrixXd A = sol.J.transpose() * sol.J;
  const Eigen::VectorXd d = A.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(d.asDiagonal() * A * d.asDiagonal());
  const auto& sv = svd.singularValues();
  if (sv(sv.size() - 1) < 1e-12 * sv(0)) {
    out.message = "the views do not constrain every parameter (J^T J is singular): add views at other tilts";
    return out;
  }
  fill_result(sol, layout, used, settings, out);
  out.ok = true;
  char buf[160];
  std::snprintf(buf, sizeof buf, "%zu views, %d residuals, %d parameters, RMS %.4f px, %d iterations",
                used.size(), out.residuals, out.free_parameters, out.rms_px, out.iterations);
  out.message = buf;
  return out;
}

}  // namespace naneye::recon
