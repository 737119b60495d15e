#pragma once
// The sources naneyed and the naneye CLI open: every scheme a source URI may name, and the NanEye
// readout boards attached to this machine.
#include <filesystem>
#include <string>
#include <vector>

#include "naneye/driver/source_registry.hpp"

namespace naneye::app {

// The driver's registry (usb://, v4l2://, file://, images://) with the simulator's sim:// added.
driver::SourceRegistry make_source_registry();

// The attached readout boards as the device profiles describe them (the *.toml of the profile folder,
// or the built-in boards when it holds none that parse).
struct BoardScan {
  std::vector<std::string> uris;  // first one first; each opens exactly that board (by serial if read)
  // One "FILE: why" per device profile that was skipped (malformed, unreadable): an operator's own
  // profile (a confirmed endpoint, a bring-up command) ignored must be said where sources are reported.
  std::vector<std::string> skipped_profiles;
};
BoardScan attached_boards(const std::filesystem::path& profile_dir);
// The same in driver::default_profile_dir().
BoardScan attached_boards();

}  // namespace naneye::app
