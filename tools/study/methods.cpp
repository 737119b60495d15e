// Every method of the comparison on every found view, scored with the paper's P, D, R (metrics.hpp) and
// against the truth (E).
#include <cmath>

#include "naneye/base/enum_table.hpp"
#include "naneye/recon/geometry/metrics.hpp"
#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/recon/paper/division_triangulation.hpp"
#include "naneye/recon/paper/plane_sweep.hpp"
#include "study.hpp"

namespace naneye::tools::study {

namespace {
constexpr base::EnumTable<Method, 8> kMethodNames{
    {{poly_tri, "polynomial, triangulated (ours: niter2 + refinement)"},
     {poly_dlt, "polynomial, exact undistortion + DLT"},
     {poly_board, "polynomial, board pose (ours)"},
     {div_tri, "division, image centre + DLT"},
     {div_sweep, "division, image centre + plane sweep"},
     {norm_tri, "division, normalized + DLT"},
     {norm_direct, "division, normalized, Eq. 10 direct (one SVD)"},
     {opencv, "OpenCV path (findChessboardCorners + cornerSubPix, undistortPoints, triangulatePoints)"}}};
}  // namespace

const char* method_name(Method m) {
  return base::enum_name(kMethodNames, m, "?");
}

namespace {

// The homography lambdas of the paper (Eq. 8-9): one plane per found view, one lambda per camera.
recon::DivisionLambdas estimate_lambdas(const Dataset& d, recon::DivisionVariant variant) {
  const recon::DivisionModel fl = recon::division_frame(d.rig.left, variant);
  const recon::DivisionModel fr = recon::division_frame(d.rig.right, variant);
  std::vector<recon::PlaneCorrespondences> planes;
  for (const View& v : d.views) {
    if (!v.found) continue;
    recon::PlaneCorrespondences pc;
    for (std::size_t i = 0; i < v.detected.size(); ++i) {
      if (!v.detected[i]) continue;
      pc.left.push_back(fl.to_model(v.left_px[i]));
      pc.right.push_back(fr.to_model(v.right_px[i]));
    }
    if (pc.left.size() >= 8) planes.push_back(std::move(pc));
  }
  if (planes.empty()) return {};
  return recon::estimate_division_lambdas(planes);
}

// R against the pixels the method itself measured (the OpenCV path has its own corners).
Scores score(const Dataset& d, const View& v, const std::vector<Eigen::Vector3d>& pts,
             const recon::DivisionRig* div, bool own_corners = false) {
  Scores s;
  const auto& l = own_corners ? v.opencv_left : v.left_px;
  const auto& r = own_corners ? v.opencv_right : v.right_px;
  s.P = recon::planarity_error(pts).value_or(NAN);
  s.D = recon::distance_error(pts, d.board.rows, d.board.cols, d.board.square_mm).value_or(NAN);
  s.R = (div ? recon::division_reprojection_error(*div, pts, l, r)
             : recon::reprojection_error(d.rig, pts, l, r))
            .value_or(NAN);
  double sq = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (!pts[i].allFinite()) continue;
    sq += (pts[i] - v.truth_mm[i]).squaredNorm();
    ++s.valid;
  }
  if (s.valid > 0) s.E = std::sqrt(sq / s.valid);
  return s;
}

}  // namespace

void run_methods(Dataset& d, const Dataset* lambda_source) {
  d.mean = {};
  const Dataset& ls = lambda_source ? *lambda_source : d;
  d.lambdas_pixel = estimate_lambdas(ls, recon::DivisionVariant::image_centre);
  d.lambdas_normalized = estimate_lambdas(ls, recon::DivisionVariant::normalized);
  const recon::DivisionRig dp = recon::make_division_rig(
      d.rig, recon::DivisionVariant::image_centre, d.lambdas_pixel.lambda_left, d.lambdas_pixel.lambda_right);
  const recon::DivisionRig dn =
      recon::make_division_rig(d.rig, recon::DivisionVariant::normalized, d.lambdas_normalized.lambda_left,
                               d.lambdas_normalized.lambda_right);
  const std::size_t n = static_cast<std::size_t>(d.board.rows * d.board.cols);
  std::array<std::array<double, 4>, kMethodCount> sums{};
  std::array<std::array<int, 4>, kMethodCount> counts{};
  const auto accumulate = [&](std::size_t m, const Scores& s) {
    const std::array<double, 4> vals{s.P, s.D, s.R, s.E};
    for (std::size_t k = 0; k < 4; ++k) {
      if (!std::isfinite(vals[k])) continue;
      sums[m][k] += vals[k];
      ++counts[m][k];
    }
    d.mean[m].valid += s.valid;
  };
  for (View& v : d.views) {
    // The OpenCV path is scored on every view it found, whether or not ours did.
    if (v.opencv_found) {
      v.scores[opencv] = score(d, v, v.points[opencv], nullptr, true);
      accumulate(opencv, v.scores[opencv]);
    }
    if (!v.found) continue;
    for (std::size_t i = 0; i < n; ++i) {
      if (v.detected[i])
        v.points[poly_dlt][i] =
            recon::triangulate(d.rig, v.left_px[i], v.right_px[i], recon::TriangulationMethod::dlt, 0.2).X;
    }
    // A corner one eye missed stays NaN on both sides, so the division paths see it as refused.
    v.points[div_tri] = recon::triangulated_points(
        recon::triangulate_undistorted(dp, v.left_px, v.right_px, recon::TriangulationMethod::dlt));
    v.points[div_sweep] = recon::sweep_points(recon::plane_sweep_division(dp, v.left_px, v.right_px));
    v.points[norm_tri] = recon::triangulated_points(
        recon::triangulate_undistorted(dn, v.left_px, v.right_px, recon::TriangulationMethod::dlt));
    v.points[norm_direct] =
        recon::triangulate_distorted(dn, v.left_px, v.right_px, recon::DirectSolve::one_svd).points;
    for (int m = 0; m < opencv; ++m) {
      const bool division = m >= div_tri;
      const recon::DivisionRig* rig = !division ? nullptr : (m == div_tri || m == div_sweep ? &dp : &dn);
      v.scores[static_cast<std::size_t>(m)] = score(d, v, v.points[static_cast<std::size_t>(m)], rig);
      accumulate(static_cast<std::size_t>(m), v.scores[static_cast<std::size_t>(m)]);
    }
  }
  for (std::size_t m = 0; m < kMethodCount; ++m) {
    double* out[4] = {&d.mean[m].P, &d.mean[m].D, &d.mean[m].R, &d.mean[m].E};
    for (std::size_t k = 0; k < 4; ++k) *out[k] = counts[m][k] ? sums[m][k] / counts[m][k] : NAN;
  }
}

}  // namespace naneye::tools::study
