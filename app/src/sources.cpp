#include "naneye/app/sources.hpp"

#include <spdlog/spdlog.h>

#include "naneye/driver/device_list.hpp"
#include "naneye/driver/usb_profile.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::app {

driver::SourceRegistry make_source_registry() {
  driver::SourceRegistry registry = driver::make_default_registry();
  sim::register_sim_source(registry);  // sim://: rendered live, for demos without a camera
  return registry;
}

std::vector<std::string> attached_boards() {
  // The boards of the device profiles (config/devices/), or the built-in ones when none are
  // installed; each entry's URI opens exactly that board (by serial when it could be read).
  std::vector<driver::UsbProfile> profiles;
  try {
    profiles = driver::load_usb_profiles(driver::default_profile_dir());
  } catch (const std::exception& e) {
    // An unreadable profile folder must not stop the fallback to the built-in boards, but an
    // operator whose own profile is ignored must be told why.
    if (auto log = spdlog::get("daemon"))
      log->warn("device profiles in {} not read ({}); using the built-in ones",
                driver::default_profile_dir().string(), e.what());
  }
  if (profiles.empty()) profiles = driver::builtin_usb_profiles();
  std::vector<std::string> uris;
  for (const auto& board : driver::list_usb_boards(profiles)) uris.push_back(board.uri);
  return uris;
}

}  // namespace naneye::app
