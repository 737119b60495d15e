#pragma once
// The paper's Dataset 3 calibration (config/calib/paper-d3.yaml), loaded once per test binary: the
// rig the corner and calibration tests render and measure with.
#include <filesystem>

#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye::test {

inline const recon::StereoRig& paper_d3() {
  static const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  return rig;
}

}  // namespace naneye::test
