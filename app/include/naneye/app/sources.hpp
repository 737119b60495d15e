#pragma once
// The sources naneyed and the naneye CLI open: every scheme a source URI may name, and the NanEye
// readout boards attached to this machine.
#include <string>
#include <vector>

#include "naneye/driver/source_registry.hpp"

namespace naneye::app {

// The driver's registry (usb://, v4l2://, file://, images://) with the simulator's sim:// added.
driver::SourceRegistry make_source_registry();

// URIs of the attached readout boards as the driver enumerates them, first one first (empty when the
// driver cannot enumerate).
std::vector<std::string> attached_boards();

}  // namespace naneye::app
