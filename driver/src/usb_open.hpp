#pragma once
// Finding and bringing up a board (internal to the usb:// transport and `naneye devices`).
#include <libusb.h>

#include <cstdint>
#include <string>
#include <vector>

#include "naneye/driver/usb_profile.hpp"

namespace naneye::driver::usb_detail {

struct Found {
  libusb_device_handle* handle = nullptr;
  int bus = 0, address = 0;
  std::string serial;
};

// Opens the first device with the profile's ids (and `serial`, when not empty). handle == nullptr
// when none could be opened; `why` then says what was seen.
Found open_matching(libusb_context* ctx, const UsbProfile& profile, const std::string& serial,
                    std::string& why);

// The serial number string of an open device, or "" when it has none or it cannot be read.
std::string read_serial(libusb_device_handle* h, std::uint8_t index);

// Runs the profile's bring-up command through /bin/sh with the NANEYE_USB_* variables set; returns
// its exit status (127 when it cannot be started).
int run_bringup_command(const std::string& command, const UsbProfile& profile, const Found& dev);

// "10f8:c487 bus 1 dev 4 serial X"
std::string describe(const UsbProfile& profile, const Found& dev);

}  // namespace naneye::driver::usb_detail
