#pragma once
// From settings.source_uri to the URI the pipeline opens. "auto" picks the first attached NanEye
// readout board and, without one, the bundled sample capture (looping real-time replay), and says
// which and why (device profiles that were skipped included: the reason shows in /v1/status).
#include <functional>

#include "naneye/app/sources.hpp"
#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/settings.hpp"

namespace naneye::daemon {

// The attached readout boards (app::attached_boards in naneyed).
using BoardLister = std::function<app::BoardScan()>;

// Throws SettingsError (naming source.sample_capture) when "auto" finds neither.
SourceChoice choose_source(const Settings& settings, const BoardLister& boards);

// The pipeline's opener over app::make_source_registry() (every scheme, sim:// included).
SourceOpener driver_source_factory();

}  // namespace naneye::daemon
