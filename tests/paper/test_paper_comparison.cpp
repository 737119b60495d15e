// The paper's "Distortion Models: Comparison" (Dias et al., ICDSC 2016, Table "Comparison of distortion
// models"): six points 2.189 mm apart, projected with the polynomial Dataset 3 model and pose, then
// reconstructed with the polynomial model and with one-parameter division models whose lambdas come from
// plane homographies, as the paper computed them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "division_scene.hpp"
#include "naneye/recon/geometry/metrics.hpp"
#include "naneye/recon/paper/division_fit.hpp"
#include "naneye/recon/paper/division_homography.hpp"
#include "naneye/recon/paper/division_triangulation.hpp"
#include "naneye/recon/paper/plane_sweep.hpp"

using namespace naneye::recon;
using namespace division_test;

namespace {

bool in_image(const CameraModel& c, const Eigen::Vector2d& p) {
  return p.x() >= -0.5 && p.y() >= -0.5 && p.x() <= c.width() - 0.5 && p.y() <= c.height() - 0.5;
}

// lambda, lambda' from the homographies of 19 Dataset-3-like boards rendered with the polynomial model.
DivisionLambdas estimate_from_boards(const StereoRig& rig, DivisionVariant variant) {
  const BoardGeometry b;
  const DivisionModel fl = division_frame(rig.left, variant), fr = division_frame(rig.right, variant);
  std::vector<PlaneCorrespondences> planes;
  for (const auto& s : dataset3_boards(b)) {
    PlaneCorrespondences pc;
    for (int r = 0; r < b.rows; ++r) {
      for (int c = 0; c < b.cols; ++c) {
        const Eigen::Vector3d X = s.R * b.corner(r, c) + s.t;
        const Eigen::Vector2d pl = rig.left.project(X), pr = rig.right.project(rig.R * X + rig.T);
        if (!rig.left.in_domain(pl) || !rig.right.in_domain(pr) || !in_image(rig.left, pl) ||
            !in_image(rig.right, pr)) {
          continue;
        }
        pc.left.push_back(fl.to_model(pl));
        pc.right.push_back(fr.to_model(pr));
      }
    }
    if (pc.left.size() >= 8) planes.push_back(pc);
  }
  return estimate_division_lambdas(planes);
}

// The same, computed once per variant for the whole binary (the rig is always Dataset 3).
const DivisionLambdas& lambdas_from_boards(const StereoRig& rig, DivisionVariant variant) {
  static const DivisionLambdas pix = estimate_from_boards(rig, DivisionVariant::image_centre);
  static const DivisionLambdas nrm = estimate_from_boards(rig, DivisionVariant::normalized);
  return variant == DivisionVariant::image_centre ? pix : nrm;
}

struct Scores {
  double P, D, R_own, R_true;
};

struct SixPoints {
  std::vector<Eigen::Vector3d> truth;
  std::vector<Eigen::Vector2d> left, right;
};

SixPoints project(const StereoRig& rig, std::vector<Eigen::Vector3d> truth) {
  SixPoints s;
  s.truth = std::move(truth);
  for (const auto& X : s.truth) {
    s.left.push_back(rig.left.project(X));
    s.right.push_back(rig.right.project(rig.R * X + rig.T));
  }
  return s;
}

// Centre: the same 2 x 3 grid as tests/paper/test_paper_synthetic.cpp, ~70 mm away, tilted, within ~8 px of
// the principal point. The paper does not say where its six points were.
SixPoints central_points(const StereoRig& rig) {
  const Eigen::Matrix3d tilt =
      (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  std::vector<Eigen::Vector3d> truth;
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) {
      truth.push_back(Eigen::Vector3d(-2.0, -1.0, 70.0) + tilt * Eigen::Vector3d(c * 2.189, r * 2.189, 0));
    }
  }
  return project(rig, truth);
}

// A fronto-parallel 2 x 3 grid at depth z whose centre lies at (field z, field z, z): along the image
// diagonal, field = 0.4 puts it ~109 px from the left principal point.
SixPoints field_points(const StereoRig& rig, double z, double field) {
  std::vector<Eigen::Vector3d> truth;
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) {
      truth.emplace_back(field * z + (c - 1) * 2.189, field * z + (r - 0.5) * 2.189, z);
    }
  }
  return project(rig, truth);
}

Scores score(const StereoRig& rig, const DivisionRig* div, const std::vector<Eigen::Vector3d>& rec,
             const SixPoints& s) {
  Scores out;
  out.P = planarity_error(rec).value_or(NAN);
  out.D = distance_error(rec, 2, 3, 2.189).value_or(NAN);
  out.R_true = reprojection_error(rig, rec, s.left, s.right).value_or(NAN);
  out.R_own = div ? division_reprojection_error(*div, rec, s.left, s.right).value_or(NAN) : out.R_true;
  return out;
}

void print(const char* name, const Scores& s, const char* paper) {
  std::printf("  %-34s P %8.4f  D %8.4f  R(own) %8.3f  R(poly) %8.3f   paper: %s\n", name, s.P, s.D, s.R_own,
              s.R_true, paper);
}

struct Methods {
  Scores poly, tri, sweep, ntri, ndir;
  int refused = 0;  // division-path points refused (outside a domain, behind a camera)
};

Methods run_all(const StereoRig& rig, const DivisionRig& dp, const DivisionRig& dn, const SixPoints& s) {
  Methods m;
  std::vector<Eigen::Vector3d> poly;
  for (std::size_t i = 0; i < s.truth.size(); ++i) {
    poly.push_back(triangulate(rig, s.left[i], s.right[i], TriangulationMethod::dlt, 0.2).X);
  }
  m.poly = score(rig, nullptr, poly, s);
  const auto tri =
      triangulated_points(triangulate_undistorted(dp, s.left, s.right, TriangulationMethod::dlt));
  const auto sweep = sweep_points(plane_sweep_division(dp, s.left, s.right));
  const auto ntri =
      triangulated_points(triangulate_undistorted(dn, s.left, s.right, TriangulationMethod::dlt));
  const auto ndir = triangulate_distorted(dn, s.left, s.right, DirectSolve::one_svd).points;
  for (const auto* v : {&tri, &sweep, &ntri, &ndir}) {
    for (const auto& X : *v) m.refused += X.allFinite() ? 0 : 1;
  }
  m.tri = score(rig, &dp, tri, s);
  m.sweep = score(rig, &dp, sweep, s);
  m.ntri = score(rig, &dn, ntri, s);
  m.ndir = score(rig, &dn, ndir, s);
  return m;
}

void print_all(const char* title, const Methods& m) {
  std::printf("%s (P, D in mm; R in px; R(own) with the method's model, R(poly) with the true one):\n",
              title);
  print("polynomial, exact undistort + DLT", m.poly, "P 0.256 D 0.628 R 0.863");
  print("division (image centre) + DLT", m.tri, "P 0.008 D 9.291 R 57.556");
  print("division (image centre) + sweep", m.sweep, "P 0.006 D 9.283 R 59.374");
  print("division (normalized) + DLT", m.ntri, "-");
  print("division (normalized) direct, 1 SVD", m.ndir, "-");
  std::printf("  division points refused: %d of 24\n", m.refused);
}

}  // namespace

TEST(PaperComparison, DivisionModelCannotStandInForThePolynomial) {
  const StereoRig rig = rig_d3();
  // The lambdas as the paper computed them: plane homographies between the views of 19 boards.
  const DivisionLambdas& pix = lambdas_from_boards(rig, DivisionVariant::image_centre);
  const DivisionLambdas& nrm = lambdas_from_boards(rig, DivisionVariant::normalized);
  ASSERT_TRUE(pix.ok && nrm.ok);
  std::printf(
      "lambda from homographies: image centre %.4g / %.4g px^-2 (transfer RMS %.3f px), "
      "normalized %.4f / %.4f (transfer RMS %.3g); LM iterations %d, %d\n",
      pix.lambda_left, pix.lambda_right, pix.rms, nrm.lambda_left, nrm.lambda_right, nrm.rms, pix.iterations,
      nrm.iterations);
  // Barrel distortion: negative lambdas; but far weaker than the least-squares fit to the camera
  // (test_division_fit.cpp: ~-8.9e-6 px^-2), because with a 1 mm baseline the inter-view homography barely
  // sees a distortion common to both eyes.
  EXPECT_LT(pix.lambda_left, 0.0);
  EXPECT_LT(pix.lambda_right, 0.0);
  const DivisionRig dp =
      make_division_rig(rig, DivisionVariant::image_centre, pix.lambda_left, pix.lambda_right);
  const DivisionRig dn =
      make_division_rig(rig, DivisionVariant::normalized, nrm.lambda_left, nrm.lambda_right);

  const Methods centre = run_all(rig, dp, dn, central_points(rig));
  print_all("Six points 2.189 mm apart near the image centre, ~70 mm", centre);
  const Methods outer = run_all(rig, dp, dn, field_points(rig, 70.0, 0.4));
  print_all("Six points 2.189 mm apart in the outer field (~109 px off-centre), 70 mm", outer);

  // The polynomial path is exact wherever the points are.
  for (const auto* m : {&centre, &outer}) {
    EXPECT_LT(m->poly.P, 1e-6);
    EXPECT_LT(m->poly.D, 1e-6);
    EXPECT_LT(m->poly.R_true, 1e-6);
  }
  // Near the centre both eyes distort alike and the division model errs by micrometres: the paper's
  // D of 9.3 mm cannot come from central points. Still not exact.
  for (const Scores* s : {&centre.tri, &centre.sweep, &centre.ntri, &centre.ndir}) {
    EXPECT_GT(s->D, 1e-4);
    EXPECT_LT(s->D, 0.05);
  }
  EXPECT_EQ(centre.refused, 0);
  // In the outer field the single parameter fails. D rises steeply with the radius
  // (ErrorGrowsWithImageRadius: 0.9 mm at 97 px, 10 mm at 109 px, 150 mm at 119 px); at ~109 px it is of the
  // paper's order (9.3 mm; asserted within 10x), with pixels of reprojection error against the true camera,
  // for both variants, while the polynomial stays exact. (The paper does not say where its points were; its R
  // of 57 px is not reproduced: ours stays below ~11 px.)
  for (const Scores* s : {&outer.tri, &outer.sweep, &outer.ntri, &outer.ndir}) {
    EXPECT_GT(s->D, 9.291 / 10);
    EXPECT_LT(s->D, 9.291 * 10);
    EXPECT_GT(s->R_true, 1.0);
    EXPECT_GT(s->D, 1e6 * outer.poly.D);
  }
  // The paper's observation that sweep and triangulation agree holds here too.
  EXPECT_NEAR(outer.sweep.D, outer.tri.D, 0.05 * outer.tri.D);
}

// The division residual against the field: the error grows with the image radius. Printed for the docs.
TEST(PaperComparison, ErrorGrowsWithImageRadius) {
  const StereoRig rig = rig_d3();
  const DivisionLambdas& pix = lambdas_from_boards(rig, DivisionVariant::image_centre);
  ASSERT_TRUE(pix.ok);
  const DivisionRig dp =
      make_division_rig(rig, DivisionVariant::image_centre, pix.lambda_left, pix.lambda_right);
  const DivisionRig dn = make_division_rig(rig, DivisionVariant::normalized, -0.1, -0.1);
  std::printf("division (image centre, homography lambdas) + DLT, 2 x 3 grid at 70 mm along the diagonal:\n");
  std::vector<double> d;
  for (const double field : {0.0, 0.15, 0.3, 0.35, 0.4, 0.45}) {
    const SixPoints s = field_points(rig, 70.0, field);
    const Methods m = run_all(rig, dp, dn, s);
    std::printf("  field %.2f (%.0f px off-centre): D %.4f mm, R(poly) %.3f px\n", field,
                (s.left[1] - Eigen::Vector2d(rig.left.cx(), rig.left.cy())).norm(), m.tri.D, m.tri.R_true);
    d.push_back(m.tri.D);
  }
  EXPECT_LT(d[0], d[2]);
  EXPECT_GT(d[5], 10.0 * d[0]);
}
