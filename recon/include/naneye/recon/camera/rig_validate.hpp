#pragma once
// Whether a calibration describes a camera pair that can exist, whatever sensor it is used with.
// A calibration that parses is not yet one to use: `naneye calib info` took a distortion of 1e300,
// and an image_width of 100000 made naneyed's worker build maps of 10^10 pixels (std::bad_alloc).
// Shared by the daemon (daemon/src/rig_check.cpp adds the sensor's size) and the command line.
#include <optional>
#include <string>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon {

// The first reason `rig` is not a usable calibration, or nullopt. Checked: image size, finite
// values, camera matrix shape, focal length, principal point inside the image, distortion
// coefficients, a valid domain (the fold of the distortion model) that is not a speck, R a rotation,
// baseline. Each bound's unit and reason are in rig_validate.cpp.
std::optional<std::string> rig_problem(const StereoRig& rig);

}  // namespace naneye::recon
