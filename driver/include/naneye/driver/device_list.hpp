#pragma once
// What is attached: NanEye readout boards on USB (by the ids of the device profiles) and V4L2 capture
// nodes with their formats and frame sizes. Used by `naneye devices`; never throws for a device that
// cannot be opened (the entry carries the reason instead).
#include <cstdint>
#include <string>
#include <vector>

#include "naneye/driver/usb_profile.hpp"

namespace naneye::driver {

struct UsbBoardInfo {
  std::uint16_t vid = 0, pid = 0;
  int bus = 0, address = 0;
  std::string serial;   // empty when unreadable (see note)
  std::string profile;  // profile name
  std::string label;
  std::string uri;   // usb://vid:pid?serial=... to open exactly this board
  std::string note;  // e.g. "cannot open: Access denied (insufficient permissions)"
};

struct V4l2FrameSize {
  std::uint32_t width = 0, height = 0;  // for stepwise/continuous ranges: the maximum
  bool range = false;
};
struct V4l2FormatInfo {
  std::string fourcc;  // "Y10 ", "GREY"...
  std::string description;
  bool usable = false;  // one of Y10, Y16, GREY, SGRBG10
  std::vector<V4l2FrameSize> sizes;
};
struct V4l2DeviceInfo {
  std::string path;  // /dev/videoN
  std::string name;  // sysfs name or card
  std::string driver;
  bool capture = false;
  std::vector<V4l2FormatInfo> formats;
  std::string note;
};

std::vector<UsbBoardInfo> list_usb_boards(const std::vector<UsbProfile>& profiles);
// Capture nodes found under /sys/class/video4linux (the way v4l2-ctl finds them).
std::vector<V4l2DeviceInfo> list_v4l2_devices();

}  // namespace naneye::driver
