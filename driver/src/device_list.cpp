#include "naneye/driver/device_list.hpp"

#include <fcntl.h>
#include <libusb.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <fmt/format.h>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "naneye/driver/v4l2_source.hpp"
#include "usb_open.hpp"
#include "v4l2_device.hpp"

namespace naneye::driver {

std::vector<UsbBoardInfo> list_usb_boards(const std::vector<UsbProfile>& profiles) {
  std::vector<UsbBoardInfo> out;
  libusb_context* ctx = nullptr;
  if (libusb_init(&ctx) != 0) return out;
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  for (ssize_t i = 0; i < n; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0) continue;
    auto p = std::find_if(profiles.begin(), profiles.end(),
                          [&](const UsbProfile& x) { return x.vid == d.idVendor && x.pid == d.idProduct; });
    if (p == profiles.end()) continue;
    UsbBoardInfo b;
    b.vid = d.idVendor;
    b.pid = d.idProduct;
    b.bus = libusb_get_bus_number(list[i]);
    b.address = libusb_get_device_address(list[i]);
    b.profile = p->name;
    b.label = p->label;
    libusb_device_handle* h = nullptr;
    if (const int r = libusb_open(list[i], &h); r == 0) {
      b.serial = usb_detail::read_serial(h, d.iSerialNumber);
      libusb_close(h);
    } else {
      b.note = std::string("cannot open: ") + libusb_strerror(r);
    }
    b.uri =
        fmt::format("usb://{:04x}:{:04x}", b.vid, b.pid) + (b.serial.empty() ? "" : "?serial=" + b.serial);
    out.push_back(std::move(b));
  }
  if (n > 0) libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return out;
}

namespace {

bool usable(std::uint32_t f) {
  for (auto x : {V4l2Format::y10, V4l2Format::y16, V4l2Format::grey, V4l2Format::sgrbg10})
    if (fourcc(x) == f) return true;
  return false;
}

void query(int fd, V4l2DeviceInfo& dev) {
  v4l2_capability cap{};
  if (ioctl(fd, VIDIOC_QUERYCAP, &cap) < 0) {
    dev.note = std::string("VIDIOC_QUERYCAP: ") + std::strerror(errno);
    return;
  }
  dev.driver = reinterpret_cast<const char*>(cap.driver);
  if (dev.name.empty()) dev.name = reinterpret_cast<const char*>(cap.card);
  const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  dev.capture = (caps & V4L2_CAP_VIDEO_CAPTURE) && (caps & V4L2_CAP_STREAMING);
  for (std::uint32_t i = 0; dev.capture && i < 64; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (ioctl(fd, VIDIOC_ENUM_FMT, &d) < 0) break;
    V4l2FormatInfo f;
    f.fourcc = v4l2_detail::fourcc_text(d.pixelformat);
    f.description = reinterpret_cast<const char*>(d.description);
    f.usable = usable(d.pixelformat);
    for (std::uint32_t j = 0; j < 64; ++j) {
      v4l2_frmsizeenum s{};
      s.index = j;
      s.pixel_format = d.pixelformat;
      if (ioctl(fd, VIDIOC_ENUM_FRAMESIZES, &s) < 0) break;
      if (s.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
        f.sizes.push_back({s.discrete.width, s.discrete.height, false});
      } else {
        f.sizes.push_back({s.stepwise.max_width, s.stepwise.max_height, true});
        break;
      }
    }
    dev.formats.push_back(std::move(f));
  }
}

}  // namespace

std::vector<V4l2DeviceInfo> list_v4l2_devices() {
  std::vector<V4l2DeviceInfo> out;
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator("/sys/class/video4linux", ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("video", 0) == 0) names.push_back(n);
  }
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
    return a.size() != b.size() ? a.size() < b.size() : a < b;
  });
  for (const auto& n : names) {
    V4l2DeviceInfo dev;
    dev.path = "/dev/" + n;
    std::ifstream name_file("/sys/class/video4linux/" + n + "/name");
    std::getline(name_file, dev.name);
    const int fd = ::open(dev.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      dev.note = std::string("cannot open: ") + std::strerror(errno);
    } else {
      query(fd, dev);
      ::close(fd);
    }
    out.push_back(std::move(dev));
  }
  return out;
}

}  // namespace naneye::driver
