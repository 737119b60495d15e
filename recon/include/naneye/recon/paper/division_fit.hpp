#pragma once
// How well can one division parameter stand in for the polynomial model? Fit lambda to a calibrated
// polynomial camera by least squares over its valid domain and report the residual against radius.
//
// For every sampled pixel p of the image inside the polynomial model's domain, the exact undistortion
// gives the pinhole pixel u = K x_n of the same ray. The division model of `variant` predicts the raw pixel
// of u as distort(u) (the inverse of Eq. 7, centred on the image centre or on the principal point). The
// residual |distort(u) - p| is measured in raw pixels, where corner detection errors live; lambda minimises
// the sum of its squares (linear start from Eq. 7 multiplied out, then Gauss-Newton in lambda alone).

#include <vector>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/paper/division_rig.hpp"

namespace naneye::recon {

struct RadialResidual {
  double radius_px = 0;    // |p - centre of distortion| of the raw pixel
  double residual_px = 0;  // |division prediction - p|
};

struct DivisionFit {
  bool ok = false;
  double lambda = 0;  // px^-2 (image_centre) or dimensionless (normalized)
  DivisionModel model;
  double rms_px = 0, max_px = 0;
  int samples_used = 0;
  std::vector<RadialResidual> samples;  // one per sampled pixel, in raster order
};

// Pixels on a grid of `step_px` (1 = every pixel) over the image; those outside the polynomial domain are
// skipped.
DivisionFit fit_division_to_camera(const CameraModel& cam, DivisionVariant variant, int step_px = 2);

// The residual of a given division model against the camera, on the same samples (e.g. lambda from
// homographies rather than from the fit).
DivisionFit division_residuals(const CameraModel& cam, const DivisionModel& model, int step_px = 2);

}  // namespace naneye::recon
