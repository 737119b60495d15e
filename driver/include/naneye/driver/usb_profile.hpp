#pragma once
// A USB readout board described by a small TOML file under config/devices/ (see docs/drivers-devices.md):
// which device to open, where the image bytes come from, and what to send it before streaming.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace naneye::driver {

// One vendor control transfer (host to device) sent after the interface is claimed.
struct UsbControlTransfer {
  std::uint8_t request_type = 0x40;  // vendor | device | host-to-device
  std::uint8_t request = 0;
  std::uint16_t value = 0;
  std::uint16_t index = 0;
  std::vector<std::uint8_t> data;
  std::string note;
};

struct UsbProfile {
  std::string name;   // e.g. "cesys-nanousb2"
  std::string label;  // human-readable
  std::uint16_t vid = 0;
  std::uint16_t pid = 0;
  int interface = 0;
  int alt_setting = -1;  // < 0: leave the default alternate setting
  std::uint8_t endpoint = 0x86;
  bool endpoint_confirmed = false;  // seen on hardware
  int transfer_count = 8;
  int transfer_size = 128 * 1024;
  // The site's FPGA bitstream / firmware bring-up: a shell command run before the interface is
  // claimed, every time the board (re)appears. The CESYS protocol is not public, so the project
  // cannot do this step itself. Empty: none. Environment: NANEYE_USB_BUS, NANEYE_USB_ADDRESS,
  // NANEYE_USB_VID, NANEYE_USB_PID, NANEYE_USB_SERIAL. A non-zero exit fails that attempt.
  std::string bringup_command;
  std::vector<UsbControlTransfer> start_controls;
};

// Throws std::runtime_error naming the file and the key when the file is malformed.
UsbProfile load_usb_profile(const std::filesystem::path& file);
UsbProfile parse_usb_profile(const std::string& toml_text, const std::string& origin);

// Where the profiles live: $NANEYE_DEVICE_PROFILES, else the installed share dir, else the source tree.
std::filesystem::path default_profile_dir();
// Every *.toml of `dir`, sorted by name; files that do not parse are skipped with a warning naming the
// file and the reason, which also goes into `skipped` when given (for a caller that reports it).
std::vector<UsbProfile> load_usb_profiles(const std::filesystem::path& dir,
                                          std::vector<std::string>* skipped = nullptr);
// The profile for vid:pid in `dir`, if any.
std::optional<UsbProfile> find_usb_profile(const std::filesystem::path& dir, std::uint16_t vid,
                                           std::uint16_t pid);
// The boards named in the stream spec, for when no profile directory is installed.
std::vector<UsbProfile> builtin_usb_profiles();

}  // namespace naneye::driver
