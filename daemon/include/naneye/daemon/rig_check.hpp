#pragma once
// Whether a calibration can run on the attached sensor, checked before the daemon takes it (at
// start, on SIGHUP and by --check-config). A calibration that parses is not yet one to use: an
// image_width of 100000 made the worker build maps of 10^10 pixels (std::bad_alloc, the worker
// aborted), and a size other than the sensor's was "reloaded" and no board was found from then on.
#include <optional>
#include <string>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::daemon {

// The first reason `rig` cannot be used with a `sensor_px` x `sensor_px` sensor, or nullopt: its
// image size must be the sensor's, and recon::rig_problem (naneye/recon/camera/rig_validate.hpp) must pass.
std::optional<std::string> rig_problem(const recon::StereoRig& rig, int sensor_px);

}  // namespace naneye::daemon
