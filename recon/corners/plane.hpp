#pragma once
// The "grid is the image of a plane" check of the corner detector, without heap allocation (it
// runs on every tracked frame).
#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

// RMS and worst residual (pixels, scaled by fx) of a homography from board coordinates (col, row)
// to the undistorted normalized corners, from the normal equations of the normalised DLT (Hartley &
// Zisserman, Alg. 4.2) with fixed-size Eigen storage. Corners beyond the fold are left out; fewer than 8
// usable corners gives false.
bool grid_plane_residual(const CornerResult& r, const CameraModel& cam, double& rms_px, double& worst_px);

}  // namespace naneye::recon
