#include "usb_emulator.hpp"

#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace naneye::test {
namespace {

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string s;
  char b[3];
  for (auto v : bytes) {
    std::snprintf(b, sizeof b, "%02x", v);
    s += b;
  }
  return s;
}

void put16(std::vector<std::uint8_t>& v, std::uint16_t x) {
  v.push_back(static_cast<std::uint8_t>(x & 0xFF));
  v.push_back(static_cast<std::uint8_t>(x >> 8));
}

// Device, configuration, interface and endpoint descriptors as sysfs "descriptors" holds them.
std::vector<std::uint8_t> descriptors(const UsbDeviceSpec& s) {
  std::vector<std::uint8_t> d = {18, 1};
  put16(d, 0x0200);
  d.insert(d.end(), {0xFF, 0x00, 0x00, 64});
  put16(d, s.vid);
  put16(d, s.pid);
  put16(d, 0x0100);
  d.insert(d.end(), {1, 2, 3, 1});
  d.insert(d.end(), {9, 2});
  put16(d, 9 + 9 + 7);
  d.insert(d.end(), {1, 1, 0, 0x80, 50});
  d.insert(d.end(), {9, 4, 0, 0, 1, 0xFF, 0, 0, 0});
  d.insert(d.end(), {7, 5, s.endpoint, 2});
  put16(d, 512);
  d.push_back(0);
  return d;
}

std::vector<std::uint8_t> string_descriptor(std::uint8_t index, const UsbDeviceSpec& s) {
  if (index == 0) return {4, 3, 0x09, 0x04};  // en-US only
  const std::string text = index == 1 ? "CESYS" : index == 2 ? "NanEye emulated" : s.serial;
  std::vector<std::uint8_t> d = {static_cast<std::uint8_t>(2 + 2 * text.size()), 3};
  for (char c : text) put16(d, static_cast<std::uint8_t>(c));
  return d;
}

usbdevfs_urb* urb_of(UMockdevIoctlData* d) {
  return reinterpret_cast<usbdevfs_urb*>(d->data);
}

}  // namespace

UsbEmulator::UsbEmulator() {
  testbed_ = umockdev_testbed_new();
  handler_ = umockdev_ioctl_base_new();
  g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(&UsbEmulator::on_ioctl), this);
}

UsbEmulator::~UsbEmulator() {
  {
    std::lock_guard lock(mutex_);
    for (auto* q : {&pending_, &ready_})
      for (auto& u : *q) g_object_unref(u.urb);
    pending_.clear();
    ready_.clear();
  }
  for (const auto& node : attached_) umockdev_testbed_detach_ioctl(testbed_, node.c_str(), nullptr);
  g_object_unref(handler_);
  g_object_unref(testbed_);
}

std::string UsbEmulator::devnode() const {
  char b[64];
  std::snprintf(b, sizeof b, "/dev/bus/usb/%03d/%03d", spec_.bus, spec_.address);
  return b;
}

std::string UsbEmulator::syspath() const {
  return "/sys/devices/emulated/usb" + std::to_string(spec_.bus) + "/naneye";
}

void UsbEmulator::plug(const UsbDeviceSpec& spec, std::vector<std::uint8_t> stream) {
  {
    std::lock_guard lock(mutex_);
    if (present_) throw std::logic_error("UsbEmulator: unplug before plugging again");
    spec_ = spec;
    stream_ = std::move(stream);
    pos_ = 0;
    served_ = 0;
    unplug_at_ = SIZE_MAX;
    // The node file was unlinked at the unplug and only add_from_string() below creates it again, so
    // no client can open it early. The device must count as present before that call: it sends the
    // "add" uevent itself, and a hotplug-driven claim can arrive before it returns (a claim refused
    // with ENODEV there made HotplugArrivalCutsTheBackoffShort flaky under load).
    gone_ = false;
    claimed_ = false;
    present_ = true;
  }
  // The handler must be in place before the "add" uevent, so that a hotplug-driven open works.
  const std::string node = devnode();
  // A replugged node gets a fresh handler registration (umockdev refuses a second one).
  if (std::find(attached_.begin(), attached_.end(), node) != attached_.end())
    umockdev_testbed_detach_ioctl(testbed_, node.c_str(), nullptr);
  else
    attached_.push_back(node);
  if (!umockdev_testbed_attach_ioctl(testbed_, node.c_str(), handler_, nullptr))
    throw std::runtime_error("umockdev_testbed_attach_ioctl failed for " + node);
  char b[16];
  std::snprintf(b, sizeof b, "%03d/%03d", spec.bus, spec.address);
  const std::string desc =
      "P: /devices/emulated/usb" + std::to_string(spec.bus) + "/naneye\nN: bus/usb/" + b +
      "\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\nE: DEVNAME=" + node + "\nE: BUSNUM=" + std::string(b, 3) +
      "\nE: DEVNUM=" + std::string(b + 4, 3) + "\nA: busnum=" + std::to_string(spec.bus) +
      "\\n\nA: devnum=" + std::to_string(spec.address) +
      "\\n\nA: speed=480\\n\nA: bConfigurationValue=1\\n\n" + "A: serial=" + spec.serial +
      "\\n\nH: descriptors=" + hex(descriptors(spec)) + "\n";
  GError* err = nullptr;
  if (!umockdev_testbed_add_from_string(testbed_, desc.c_str(), &err)) {
    std::string msg = err ? err->message : "?";
    g_clear_error(&err);
    throw std::runtime_error("umockdev_testbed_add_from_string: " + msg);
  }
}

void UsbEmulator::unplug_after(std::size_t after_bytes) {
  std::lock_guard lock(mutex_);
  unplug_at_ = pos_ + after_bytes;
  if (after_bytes == 0) remove_locked();
}

// Called with the mutex held. The kernel gives every URB in flight back with an error when the
// device goes away; libusb maps -ENODEV to LIBUSB_TRANSFER_NO_DEVICE.
void UsbEmulator::remove_locked() {
  if (gone_) return;
  gone_ = true;
  for (auto& u : pending_) {
    urb_of(u.urb)->status = -ENODEV;
    urb_of(u.urb)->actual_length = 0;
    ready_.push_back(u);
  }
  pending_.clear();
  const std::string sys = syspath();
  umockdev_testbed_uevent(testbed_, sys.c_str(), "remove");
  // remove_device() only unlinks nodes of devices with a "dev" (major:minor) attribute.
  gchar* root = umockdev_testbed_get_root_dir(testbed_);
  ::unlink((std::string(root) + devnode()).c_str());
  g_free(root);
  umockdev_testbed_remove_device(testbed_, sys.c_str());
  present_ = false;
  cv_.notify_all();
}

void UsbEmulator::fail_transfer_at(std::size_t at, int status, std::size_t lost) {
  std::lock_guard lock(mutex_);
  fail_at_ = at;
  fail_status_ = status;
  fail_lost_ = lost;
}

void UsbEmulator::refuse_claims(int count, int error) {
  std::lock_guard lock(mutex_);
  refuse_claims_ = count;
  refuse_error_ = error;
}

int UsbEmulator::claims_refused() const {
  std::lock_guard lock(mutex_);
  return claims_refused_;
}

bool UsbEmulator::wait_unplugged(int timeout_ms) {
  std::unique_lock lock(mutex_);
  return cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return gone_; });
}

std::size_t UsbEmulator::bytes_served() const {
  std::lock_guard lock(mutex_);
  return served_;
}
std::size_t UsbEmulator::max_in_flight() const {
  std::lock_guard lock(mutex_);
  return max_in_flight_;
}
std::size_t UsbEmulator::in_flight() const {
  std::lock_guard lock(mutex_);
  return pending_.size();
}
std::size_t UsbEmulator::discarded() const {
  std::lock_guard lock(mutex_);
  return discarded_;
}
bool UsbEmulator::claimed() const {
  std::lock_guard lock(mutex_);
  return claimed_;
}
std::size_t UsbEmulator::clear_halts() const {
  std::lock_guard lock(mutex_);
  return clear_halts_;
}
std::vector<ControlRecord> UsbEmulator::vendor_controls() const {
  std::lock_guard lock(mutex_);
  return controls_;
}

gboolean UsbEmulator::on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  auto* emu = static_cast<UsbEmulator*>(self);
  const bool handled = emu->handle(client);
  // libusb polls a plain file here, which is always ready: without a pause the empty reaps would
  // spin both threads at full speed while the stream is idle.
  if (emu->idle_.exchange(false)) std::this_thread::sleep_for(std::chrono::microseconds(200));
  return handled ? TRUE : FALSE;
}

bool UsbEmulator::handle(UMockdevIoctlClient* client) {
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  std::lock_guard lock(mutex_);
  const bool stale = devnode() != umockdev_ioctl_client_get_devnode(client);
  if ((gone_ || stale) && request != USBDEVFS_REAPURB && request != USBDEVFS_REAPURBNDELAY &&
      request != USBDEVFS_DISCARDURB && request != USBDEVFS_RELEASEINTERFACE) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return true;
  }
  switch (request) {
    case USBDEVFS_GET_CAPABILITIES: {
      UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(guint32), nullptr);
      *reinterpret_cast<guint32*>(d->data) =
          USBDEVFS_CAP_BULK_SCATTER_GATHER | USBDEVFS_CAP_BULK_CONTINUATION |
          USBDEVFS_CAP_NO_PACKET_SIZE_LIM | USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
      g_object_unref(d);
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    }
    case USBDEVFS_CLAIMINTERFACE:
    case USBDEVFS_DISCONNECT_CLAIM:  // libusb's auto-detach claims this way
      if (refuse_claims_ > 0) {
        --refuse_claims_;
        ++claims_refused_;
        umockdev_ioctl_client_complete(client, -1, refuse_error_);
        return true;
      }
      claimed_ = true;
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    case USBDEVFS_RELEASEINTERFACE:
      claimed_ = false;
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    case USBDEVFS_CLEAR_HALT:
      ++clear_halts_;
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    case USBDEVFS_SETINTERFACE:
    case USBDEVFS_RESET:
    case USBDEVFS_RESETEP:
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    case USBDEVFS_SUBMITURB:
      return submit(client, arg);
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY:
      return reap(client, arg);
    case USBDEVFS_DISCARDURB: {
      const auto addr = *reinterpret_cast<unsigned long*>(arg->data);
      auto it =
          std::find_if(pending_.begin(), pending_.end(), [&](const Urb& u) { return u.client_addr == addr; });
      if (it == pending_.end()) {
        umockdev_ioctl_client_complete(client, -1, EINVAL);
        return true;
      }
      urb_of(it->urb)->status = -ENOENT;
      urb_of(it->urb)->actual_length = 0;
      ready_.push_back(*it);
      pending_.erase(it);
      ++discarded_;
      umockdev_ioctl_client_complete(client, 0, 0);
      return true;
    }
    case USBDEVFS_IOCTL:  // kernel driver queries: no driver is bound to a vendor-class interface
      umockdev_ioctl_client_complete(client, -1, ENODATA);
      return true;
    default:
      umockdev_ioctl_client_complete(client, -1, ENOTTY);
      return true;
  }
}

bool UsbEmulator::submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
  usbdevfs_urb* urb = urb_of(d);
  UMockdevIoctlData* buf = umockdev_ioctl_data_resolve(d, offsetof(usbdevfs_urb, buffer),
                                                       static_cast<gsize>(urb->buffer_length), nullptr);
  if (buf) g_object_unref(buf);  // the parent keeps it; urb->buffer now points at the local copy
  Urb u{d, d->client_addr, urb->type == USBDEVFS_URB_TYPE_CONTROL, 0};
  if (u.control) {
    answer_control(u);
    ready_.push_back(u);
  } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == spec_.endpoint) {
    pending_.push_back(u);
    max_in_flight_ = std::max(max_in_flight_, pending_.size());
  } else {
    g_object_unref(d);
    umockdev_ioctl_client_complete(client, -1, EINVAL);
    return true;
  }
  umockdev_ioctl_client_complete(client, 0, 0);
  return true;
}

void UsbEmulator::answer_control(Urb& u) {
  usbdevfs_urb* urb = urb_of(u.urb);
  auto* b = static_cast<std::uint8_t*>(urb->buffer);
  ControlRecord c;
  c.request_type = b[0];
  c.request = b[1];
  c.value = static_cast<std::uint16_t>(b[2] | b[3] << 8);
  c.index = static_cast<std::uint16_t>(b[4] | b[5] << 8);
  const int length = b[6] | b[7] << 8;
  urb->status = 0;
  urb->actual_length = 0;
  if (c.request_type == 0x80 && c.request == 6 && (c.value >> 8) == 3) {  // GET_DESCRIPTOR(string)
    auto s = string_descriptor(static_cast<std::uint8_t>(c.value & 0xFF), spec_);
    const int n = std::min<int>(length, static_cast<int>(s.size()));
    std::memcpy(b + 8, s.data(), static_cast<std::size_t>(n));
    urb->actual_length = n;
  } else if ((c.request_type & 0x60) == 0x40 && !(c.request_type & 0x80)) {  // vendor, host to device
    c.data.assign(b + 8, b + 8 + length);
    controls_.push_back(c);
    urb->actual_length = length;
  } else {
    urb->status = -EPIPE;  // stall, as a device does for requests it does not know
  }
}

bool UsbEmulator::fill_bulk(Urb& u) {
  usbdevfs_urb* urb = urb_of(u.urb);
  const std::size_t end = std::min(stream_.size(), unplug_at_);
  if (pos_ >= end) return false;
  if (pos_ <= fail_at_ && fail_at_ < std::min(end, pos_ + static_cast<std::size_t>(urb->buffer_length))) {
    pos_ = std::min(end, fail_at_ + fail_lost_);
    fail_at_ = SIZE_MAX;
    urb->actual_length = 0;
    urb->status = fail_status_;
    return true;
  }
  const std::size_t n = std::min<std::size_t>(end - pos_, static_cast<std::size_t>(urb->buffer_length));
  std::memcpy(urb->buffer, stream_.data() + pos_, n);
  pos_ += n;
  served_ += n;
  urb->actual_length = static_cast<int>(n);
  urb->status = 0;
  return true;
}

bool UsbEmulator::reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg) {
  Urb u;
  if (!ready_.empty()) {
    u = ready_.front();
    ready_.pop_front();
  } else if (!pending_.empty() && !gone_ && fill_bulk(pending_.front())) {
    u = pending_.front();
    pending_.pop_front();
    if (pos_ >= unplug_at_) remove_locked();
  } else {
    if (!gone_ && pos_ >= unplug_at_) remove_locked();
    const bool gone = gone_ && ready_.empty();
    idle_ = !gone;
    umockdev_ioctl_client_complete(client, -1, gone ? ENODEV : EAGAIN);
    return true;
  }
  UMockdevIoctlData* out = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
  umockdev_ioctl_data_set_ptr(out, 0, u.urb);
  g_object_unref(out);
  umockdev_ioctl_client_complete(client, 0, 0);
  g_object_unref(u.urb);
  return true;
}

}  // namespace naneye::test
