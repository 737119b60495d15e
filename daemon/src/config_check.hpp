#pragma once
// What `naneyed --check-config` can know without opening a device: the source URI's scheme and
// parameters, the files it names (a capture must hold at least one stereo pair), a V4L2 node that
// must exist, the listen address. The calibration against the sensor is rig_check.hpp's.
#include <string>
#include <vector>

#include "naneye/daemon/settings.hpp"
#include "naneye/driver/source_registry.hpp"

namespace naneye::daemon {

// Every problem found, in words (empty: none). Reads capture files; opens no device.
std::vector<std::string> check_config(const Settings& s, const driver::SourceRegistry& registry);

}  // namespace naneye::daemon
