#pragma once
// Board views from stereo image pairs for `naneye calibrate --left ... --right ...` (calibrate_images.cpp).
#include <string>
#include <utility>
#include <vector>

#include "calibrate_views.hpp"
#include "naneye/driver/image_file.hpp"

namespace naneye::tools {

// A rig of two distortion-free pinhole cameras of this image size: the lens model when none is known.
recon::StereoRig pinhole_rig(int width, int height);

// Detects the board in both images of every pair (full search). `lens_known` false: `guess` is a
// pinhole stand-in, so grids are not tested for planarity and the right eye keeps the image-space
// numbering. Throws std::runtime_error for an unreadable image or one of another size than `guess`.
CollectedViews collect_image_views(const std::vector<std::pair<std::string, std::string>>& pairs,
                                   const recon::StereoRig& guess, recon::CornerSettings corners,
                                   bool lens_known, driver::ColorMode color, Progress& progress);

}  // namespace naneye::tools
