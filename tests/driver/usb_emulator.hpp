#pragma once
// An emulated CESYS readout board for hardware-free tests: a umockdev testbed holds the sysfs
// device (descriptors with one bulk IN endpoint) and an in-process "handle-ioctl" handler serves
// the usbdevfs ioctls libusb issues on /dev/bus/usb/BBB/DDD. Bulk IN URBs are filled from a byte
// stream the test supplies, so any number of them can be in flight (the .ioctl replay files allow
// only one). Handlers run on umockdev's worker thread; everything here is guarded by one mutex.
#include <umockdev.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

namespace naneye::test {

struct UsbDeviceSpec {
  std::uint16_t vid = 0x10f8;
  std::uint16_t pid = 0xc487;
  std::uint8_t endpoint = 0x86;
  int bus = 1;
  int address = 4;
  std::string serial = "NE0001";
};

struct ControlRecord {
  std::uint8_t request_type = 0, request = 0;
  std::uint16_t value = 0, index = 0;
  std::vector<std::uint8_t> data;
};

class UsbEmulator {
 public:
  UsbEmulator();  // creates the testbed (sets $UMOCKDEV_DIR): construct before any libusb context
  ~UsbEmulator();
  UsbEmulator(const UsbEmulator&) = delete;
  UsbEmulator& operator=(const UsbEmulator&) = delete;

  UMockdevTestbed* testbed() { return testbed_; }

  // Plugs the device in (sysfs + node + uevent). `stream` is what the bulk endpoint will deliver.
  void plug(const UsbDeviceSpec& spec, std::vector<std::uint8_t> stream);
  // Pulls the device out after `after_bytes` more bytes of its stream (0: now): pending URBs are then
  // given back with -ENODEV, later ioctls fail with ENODEV, and the sysfs device is removed.
  void unplug_after(std::size_t after_bytes);
  bool wait_unplugged(int timeout_ms);
  // The bulk URB that would carry stream byte `at` completes with `status` (e.g. -EPROTO) instead,
  // and `lost` bytes of the stream vanish with it, as on a damaged bus.
  void fail_transfer_at(std::size_t at, int status, std::size_t lost);
  // The next `count` interface claims fail with `error` (EBUSY: a board still settling after it
  // arrived, its bring-up or udev rule not done yet).
  void refuse_claims(int count, int error);
  int claims_refused() const;

  // Figures the tests check.
  std::size_t bytes_served() const;
  std::size_t max_in_flight() const;
  std::size_t in_flight() const;
  std::size_t discarded() const;
  bool claimed() const;
  std::size_t clear_halts() const;
  std::vector<ControlRecord> vendor_controls() const;

 private:
  struct Urb {
    UMockdevIoctlData* urb = nullptr;  // owned reference
    unsigned long client_addr = 0;
    bool control = false;
    int status = 0;
  };
  static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self);
  bool handle(UMockdevIoctlClient* client);
  bool submit(UMockdevIoctlClient* client, UMockdevIoctlData* arg);
  bool reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg);
  void answer_control(Urb& u);
  bool fill_bulk(Urb& u);
  void remove_locked();
  std::string devnode() const;
  std::string syspath() const;

  UMockdevTestbed* testbed_ = nullptr;
  UMockdevIoctlBase* handler_ = nullptr;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  UsbDeviceSpec spec_;
  bool present_ = false;
  bool gone_ = false;  // unplugged: ioctls fail with ENODEV
  std::vector<std::uint8_t> stream_;
  std::size_t pos_ = 0;
  std::size_t unplug_at_ = SIZE_MAX;
  std::size_t fail_at_ = SIZE_MAX, fail_lost_ = 0;
  int fail_status_ = 0;
  std::deque<Urb> pending_;  // submitted bulk IN, oldest first
  std::deque<Urb> ready_;    // completed (control, discarded, dead) waiting to be reaped
  std::size_t max_in_flight_ = 0;
  std::size_t discarded_ = 0;
  bool claimed_ = false;
  int refuse_claims_ = 0, refuse_error_ = 0, claims_refused_ = 0;
  std::size_t clear_halts_ = 0;
  std::vector<ControlRecord> controls_;
  std::size_t served_ = 0;
  std::vector<std::string> attached_;
  std::atomic<bool> idle_{false};
};

}  // namespace naneye::test
