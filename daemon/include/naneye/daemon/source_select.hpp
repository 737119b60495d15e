#pragma once
// From settings.source_uri to the URI the pipeline opens. "auto" picks the first attached NanEye
// readout board and, without one, the bundled sample capture (looping real-time replay), and says
// which and why.
#include <functional>
#include <string>
#include <vector>

#include "naneye/driver/source_registry.hpp"

#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/settings.hpp"

namespace naneye::daemon {

// URIs of the attached readout boards, first one first.
using BoardLister = std::function<std::vector<std::string>()>;

// Throws SettingsError (naming source.sample_capture) when "auto" finds neither.
SourceChoice choose_source(const Settings& settings, const BoardLister& boards);

// The driver's registry: opens usb://, v4l2://, file://, sim:// URIs.
// Every scheme a source URI may name: the driver's (usb, v4l2, file) and the simulator's sim://.
driver::SourceRegistry make_source_registry();
SourceOpener driver_source_factory();
// Attached boards as the driver enumerates them (empty when the driver cannot enumerate).
std::vector<std::string> attached_boards();

}  // namespace naneye::daemon
