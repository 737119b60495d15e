#include "naneye/app/sources.hpp"

#include "naneye/driver/device_list.hpp"
#include "naneye/driver/usb_profile.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::app {

driver::SourceRegistry make_source_registry() {
  driver::SourceRegistry registry = driver::make_default_registry();
  sim::register_sim_source(registry);  // sim://: rendered live, for demos without a camera
  return registry;
}

BoardScan attached_boards(const std::filesystem::path& profile_dir) {
  BoardScan scan;
  // load_usb_profiles logs each skipped file with its reason (the "driver" logger) and hands it back.
  std::vector<driver::UsbProfile> profiles = driver::load_usb_profiles(profile_dir, &scan.skipped_profiles);
  if (profiles.empty()) profiles = driver::builtin_usb_profiles();
  for (const auto& board : driver::list_usb_boards(profiles)) scan.uris.push_back(board.uri);
  return scan;
}

BoardScan attached_boards() {
  return attached_boards(driver::default_profile_dir());
}

}  // namespace naneye::app
