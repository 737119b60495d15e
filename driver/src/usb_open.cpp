#include "usb_open.hpp"

#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cstring>

extern char** environ;

namespace naneye::driver::usb_detail {

std::string read_serial(libusb_device_handle* h, std::uint8_t index) {
  if (index == 0) return {};
  unsigned char buf[128] = {};
  const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf - 1);
  return n > 0 ? std::string(reinterpret_cast<char*>(buf), static_cast<std::size_t>(n)) : std::string{};
}

Found open_matching(libusb_context* ctx, const UsbProfile& profile, const std::string& serial,
                    std::string& why) {
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  Found found;
  if (n < 0) {
    why = fmt::format("cannot list USB devices: {}", libusb_strerror(static_cast<int>(n)));
    return found;
  }
  int seen = 0;
  for (ssize_t i = 0; i < n && !found.handle; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || d.idVendor != profile.vid ||
        d.idProduct != profile.pid)
      continue;
    ++seen;
    libusb_device_handle* h = nullptr;
    if (const int r = libusb_open(list[i], &h); r != 0) {
      why =
          fmt::format("{:04x}:{:04x} on bus {} dev {} cannot be opened: {}", d.idVendor, d.idProduct,
                      libusb_get_bus_number(list[i]), libusb_get_device_address(list[i]), libusb_strerror(r));
      continue;
    }
    std::string s = read_serial(h, d.iSerialNumber);
    if (!serial.empty() && s != serial) {
      why = fmt::format("{:04x}:{:04x} present but serial '{}' != '{}'", d.idVendor, d.idProduct, s, serial);
      libusb_close(h);
      continue;
    }
    found = {h, libusb_get_bus_number(list[i]), libusb_get_device_address(list[i]), std::move(s)};
  }
  libusb_free_device_list(list, 1);
  if (!found.handle && seen == 0) why = fmt::format("no {:04x}:{:04x} attached", profile.vid, profile.pid);
  return found;
}

int run_bringup_command(const std::string& command, const UsbProfile& profile, const Found& dev) {
  std::vector<std::string> env_strings = {
      fmt::format("NANEYE_USB_BUS={}", dev.bus), fmt::format("NANEYE_USB_ADDRESS={}", dev.address),
      fmt::format("NANEYE_USB_VID={:04x}", profile.vid), fmt::format("NANEYE_USB_PID={:04x}", profile.pid),
      "NANEYE_USB_SERIAL=" + dev.serial};
  std::vector<char*> envp;
  for (char** e = environ; e && *e; ++e)
    if (std::strncmp(*e, "NANEYE_USB_", 11) != 0) envp.push_back(*e);
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string sh = "/bin/sh", dash_c = "-c", cmd = command;
  char* argv[] = {sh.data(), dash_c.data(), cmd.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, "/bin/sh", nullptr, nullptr, argv, envp.data()) != 0) return 127;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 127;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string describe(const UsbProfile& profile, const Found& dev) {
  std::string s = fmt::format("{:04x}:{:04x} bus {} dev {}", profile.vid, profile.pid, dev.bus, dev.address);
  if (!dev.serial.empty()) s += " serial " + dev.serial;
  return s;
}

}  // namespace naneye::driver::usb_detail
