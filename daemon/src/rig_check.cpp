#include "naneye/daemon/rig_check.hpp"

#include "naneye/recon/camera/rig_validate.hpp"

namespace naneye::daemon {

std::optional<std::string> rig_problem(const recon::StereoRig& rig, int sensor_px) {
  // The sensor's size first: a calibration for another sensor is the likelier mistake, and its
  // other values may be sane for that sensor.
  for (const auto* c : {&rig.left, &rig.right}) {
    if (c->width() != sensor_px || c->height() != sensor_px) {
      return std::string(c == &rig.left ? "left" : "right") + " camera: image size " +
             std::to_string(c->width()) + "x" + std::to_string(c->height()) + " does not match the " +
             std::to_string(sensor_px) + "x" + std::to_string(sensor_px) + " sensor";
    }
  }
  return recon::rig_problem(rig);
}

}  // namespace naneye::daemon
