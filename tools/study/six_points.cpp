// The paper's "Distortion Models: Comparison" (Table "Comparison of distortion models"): six synthetic
// points 2.189 mm apart, projected noise-free through the polynomial Dataset 3 rig, reconstructed by the
// baseline and by the division variants with the lambdas the homographies gave on the rendered views.
// The paper does not say where the points were; the result depends on it steeply
// (docs/division-model.md), so several placements are reported.
#include <Eigen/Geometry>
#include <cstdio>

#include "naneye/recon/geometry/metrics.hpp"
#include "naneye/recon/paper/division_triangulation.hpp"
#include "naneye/recon/paper/plane_sweep.hpp"
#include "study.hpp"

namespace naneye::tools::study {
namespace {

constexpr double kSpacing = 2.189;  // mm, the paper's

// A 2 x 3 grid at depth z around (field z, field z, z), turned by `tilt`: field 0 is on the axis, 0.4 puts
// the centre ~109 px from the left principal point along the image diagonal.
std::vector<Eigen::Vector3d> grid(double z, double field, const Eigen::Matrix3d& tilt) {
  std::vector<Eigen::Vector3d> pts;
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) {
      pts.push_back(Eigen::Vector3d(field * z, field * z, z) +
                    tilt * Eigen::Vector3d((c - 1) * kSpacing, (r - 0.5) * kSpacing, 0));
    }
  }
  return pts;
}

SixPointRow score(const recon::StereoRig& rig, const recon::DivisionRig* div,
                  const std::vector<Eigen::Vector3d>& rec, const std::vector<Eigen::Vector2d>& l,
                  const std::vector<Eigen::Vector2d>& r) {
  SixPointRow s;
  s.P = recon::planarity_error(rec).value_or(NAN);
  s.D = recon::distance_error(rec, 2, 3, kSpacing).value_or(NAN);
  s.R_true = recon::reprojection_error(rig, rec, l, r).value_or(NAN);
  s.R_own = div ? recon::division_reprojection_error(*div, rec, l, r).value_or(NAN) : s.R_true;
  return s;
}

}  // namespace

std::vector<SixPointResult> six_point_comparison(const Dataset& d3) {
  const recon::StereoRig& rig = d3.rig;
  const recon::DivisionRig dp = recon::make_division_rig(
      rig, recon::DivisionVariant::image_centre, d3.lambdas_pixel.lambda_left, d3.lambdas_pixel.lambda_right);
  const recon::DivisionRig dn =
      recon::make_division_rig(rig, recon::DivisionVariant::normalized, d3.lambdas_normalized.lambda_left,
                               d3.lambdas_normalized.lambda_right);
  const Eigen::Matrix3d tilted =
      (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  struct Placement {
    const char* name;
    double field;
    Eigen::Matrix3d tilt;
  };
  const Placement placements[] = {{"on the axis, tilted board", 0.0, tilted},
                                  {"mid field, fronto-parallel", 0.3, Eigen::Matrix3d::Identity()},
                                  {"outer field, fronto-parallel", 0.4, Eigen::Matrix3d::Identity()}};
  std::vector<SixPointResult> out;
  for (const Placement& p : placements) {
    const auto truth = grid(70.0, p.field, p.tilt);
    std::vector<Eigen::Vector2d> l, r;
    for (const auto& X : truth) {
      l.push_back(rig.left.project(X));
      r.push_back(rig.right.project(rig.R * X + rig.T));
    }
    SixPointResult res;
    res.placement = p.name;
    Eigen::Vector2d c(0, 0);
    for (const auto& q : l) c += q / 6.0;
    res.offset_px = (c - Eigen::Vector2d(rig.left.cx(), rig.left.cy())).norm();
    std::vector<Eigen::Vector3d> poly;
    for (std::size_t i = 0; i < truth.size(); ++i)
      poly.push_back(recon::triangulate(rig, l[i], r[i], recon::TriangulationMethod::dlt, 0.2).X);
    res.rows[poly_dlt] = score(rig, nullptr, poly, l, r);
    res.rows[div_tri] = score(
        rig, &dp,
        recon::triangulated_points(recon::triangulate_undistorted(dp, l, r, recon::TriangulationMethod::dlt)),
        l, r);
    res.rows[div_sweep] = score(rig, &dp, recon::sweep_points(recon::plane_sweep_division(dp, l, r)), l, r);
    res.rows[norm_tri] = score(
        rig, &dn,
        recon::triangulated_points(recon::triangulate_undistorted(dn, l, r, recon::TriangulationMethod::dlt)),
        l, r);
    res.rows[norm_direct] =
        score(rig, &dn, recon::triangulate_distorted(dn, l, r, recon::DirectSolve::one_svd).points, l, r);
    out.push_back(std::move(res));
  }
  return out;
}

}  // namespace naneye::tools::study
