#pragma once
// The division-model parameters of both cameras from plane homographies between the two views (Kukelova,
// Heller, Bujnak, Fitzgibbon, Pajdla, "Radial distortion homography", CVPR 2015; Dias et al., ICDSC 2016,
// Eq. 8-9): a plane point seen as x_d (left) and x'_d (right) satisfies
//   [x'_i]x H x_i = 0,  x_i = (x_d, y_d, 1 + lambda r_d^2),  x'_i = (x'_d, y'_d, 1 + lambda' r'^2_d).
// All coordinates are model coordinates of DivisionModel (A^-1 px): the solver does not care which variant.
//
// Solver (docs/division-model.md): the third row of Eq. 9 does not contain lambda', and is linear in
// v = (h11 h12 h13 h21 h22 h23 lambda h13 lambda h23): one SVD gives the first two rows of H and lambda
// (Kukelova et al. 2015, non-minimal). With those, rows one and two are linear in (h31 h32 h33 lambda'):
// a least-squares solve. Both steps are exact on noise-free data. With noise the algebraic solution is
// biased, so Levenberg-Marquardt then minimises the symmetric transfer error in the distorted images over
// H, lambda and lambda' (block-sparse normal equations, central-difference Jacobian). Several boards share
// one lambda per camera: each board is solved alone, the medians of their lambdas fix a DLT per board, and
// a joint refinement follows with one H per board.
//
// Observability: with a ~1 mm baseline the inter-view homography is close to the identity, where equal
// distortions in both views cancel, so the common part of lambda and lambda' is weakly determined
// (docs/division-model.md has the figures).

#include <Eigen/Core>
#include <span>
#include <vector>

namespace naneye::recon {

struct DivisionHomographySettings {
  bool refine = true;  // LM on the symmetric transfer error after the linear solve
  int max_iterations = 200;
};

struct DivisionHomography {
  bool ok = false;
  Eigen::Matrix3d H = Eigen::Matrix3d::Identity();  // x' ~ H x (lifted, model coords); ||H||_F = 1
  double lambda_left = 0, lambda_right = 0;
  double linear_rms = 0;  // symmetric transfer RMS per coordinate (model units) of the linear solution
  double rms = 0;         // the same after refinement (== linear_rms without it)
  int iterations = 0;
};

// One plane: corresponding distorted points (model coordinates), at least 8 of them.
DivisionHomography estimate_division_homography(std::span<const Eigen::Vector2d> left,
                                                std::span<const Eigen::Vector2d> right,
                                                const DivisionHomographySettings& opt = {});

struct PlaneCorrespondences {
  std::vector<Eigen::Vector2d> left, right;  // model coordinates, same order
};

struct DivisionLambdas {
  bool ok = false;
  double lambda_left = 0, lambda_right = 0;
  std::vector<Eigen::Matrix3d> H;  // one per plane, ||H||_F = 1
  double rms = 0;                  // symmetric transfer RMS per coordinate over every plane (model units)
  int iterations = 0;
};

// Several planes, one lambda per camera shared by all of them.
DivisionLambdas estimate_division_lambdas(std::span<const PlaneCorrespondences> planes,
                                          const DivisionHomographySettings& opt = {});

}  // namespace naneye::recon
