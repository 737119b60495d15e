#include "naneye/daemon/source_select.hpp"

#include <memory>

namespace naneye::daemon {

SourceChoice choose_source(const Settings& settings, const BoardLister& boards) {
  if (settings.source_uri != "auto") return {settings.source_uri, "configured", false};
  const auto scan = boards ? boards() : app::BoardScan{};
  // A profile the operator wrote and the scan skipped is part of why this source was chosen.
  std::string skipped;
  for (const auto& why : scan.skipped_profiles) skipped += (skipped.empty() ? "" : "; ") + why;
  if (!skipped.empty()) skipped = " (device profiles skipped: " + skipped + ")";
  if (!scan.uris.empty()) {
    return {scan.uris.front(),
            "auto: first attached NanEye readout board (" + std::to_string(scan.uris.size()) + " attached)" +
                skipped,
            false};
  }
  if (settings.sample_capture.empty()) {
    throw SettingsError(
        "source.sample_capture: source.uri is \"auto\", no NanEye readout board is attached and no sample "
        "capture "
        "is configured to fall back to" +
        skipped);
  }
  return {"file://" + settings.sample_capture.string() + "?speed=realtime&loop=1",
          "auto: no NanEye readout board attached; replaying the bundled sample capture " +
              settings.sample_capture.string() + " in a loop at real time" + skipped,
          true};
}

SourceOpener driver_source_factory() {
  auto registry = std::make_shared<driver::SourceRegistry>(app::make_source_registry());
  return [registry](const std::string& uri) { return registry->open(uri); };
}

}  // namespace naneye::daemon
