#include "naneye/daemon/source_select.hpp"
#include "naneye/driver/source_registry.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::daemon {

SourceFactory driver_source_factory() {
  auto registry = std::make_shared<driver::SourceRegistry>(driver::make_default_registry());
  sim::register_sim_source(*registry);  // sim://: rendered live, for demos without a camera
  return [registry](const std::string& uri) { return registry->open(uri); };
}

std::vector<std::string> attached_boards() {
  // The driver has no enumeration of readout boards yet (it comes with the usb:// backend); until
  // then "auto" always falls back to the sample capture, and says so.
  return {};
}

}  // namespace naneye::daemon
