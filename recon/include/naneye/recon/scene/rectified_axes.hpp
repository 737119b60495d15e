#pragma once
// The dense path's rectified frame (docs/scene.md, "Dense path"): Bouguet's construction, as in
// cv::stereoRectify. Public so that what is measured against the dense disparities (the simulator's
// Cramér-Rao bound, sim/disparity_bound.hpp) uses the same frame: d = f B / Z_rect.
#include <Eigen/Core>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon::scene {

// X_rect = rect_from_left(rig) X_left: x along the baseline, z the mean of both optical axes made
// orthogonal to it, y = z x x.
Eigen::Matrix3d rect_from_left(const StereoRig& rig);

}  // namespace naneye::recon::scene
