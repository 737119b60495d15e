#pragma once
// The libusb side of usb://: finds the board, brings it up, keeps a ring of bulk IN transfers in
// flight on its own event thread and hands every completed transfer's bytes, in arrival order, to a
// sink. It survives the board going away (waiting_for_device, reconnect with base::Backoff: its
// delays, "say why once" logging and counters; woken early by hotplug arrivals) and reports stalls. It knows
// nothing of records: the sink (the stream parser of the usb:// source, or a recorder) does.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>

#include "naneye/base/backoff.hpp"
#include "naneye/driver/frame_source.hpp"
#include "naneye/driver/usb_profile.hpp"

struct libusb_device_handle;

namespace naneye::driver {

struct UsbTransportSettings {
  UsbProfile profile;
  std::string serial;  // empty: the first board with the profile's ids
  std::chrono::milliseconds stall_timeout{1000};
  base::BackoffSettings backoff;                   // reconnect delays (base/backoff.hpp's defaults)
  std::chrono::milliseconds cancel_timeout{2000};  // shutdown: how long to wait for cancelled transfers
  // In-process bring-up, run after the external bringup_command (if any) and before the claim.
  // Returning false fails the attempt (retried with backoff).
  std::function<bool(libusb_device_handle*)> bringup;
};

class UsbTransportSink {
 public:
  virtual ~UsbTransportSink() = default;
  // One completed transfer. Called on the event thread, in the order the bytes arrived.
  virtual void on_bytes(std::span<const std::uint8_t> bytes, std::int64_t host_ns) = 0;
  // The byte stream broke (device lost, transfer error): whatever record was in flight is cut.
  virtual void on_discontinuity() = 0;
  virtual void on_state(SourceState state) = 0;
};

struct UsbTransportCounters {
  std::uint64_t bytes = 0;
  std::uint64_t transfers = 0;
  std::uint64_t transfer_errors = 0;
  std::uint64_t reconnects = 0;
  std::uint64_t stalls = 0;
  std::uint64_t connects = 0;
};

class UsbTransport {
 public:
  UsbTransport(UsbTransportSettings settings, UsbTransportSink& sink);
  ~UsbTransport();  // stops
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  // Creates the libusb context and starts the event thread; the board need not be attached yet
  // (state waiting_for_device). Throws SourceError when libusb cannot be initialised.
  void start();
  // Cancels every transfer in flight, waits for their callbacks, releases and closes; idempotent.
  void stop();
  SourceState state() const { return state_.load(); }
  UsbTransportCounters counters() const;
  std::string device_description() const;  // "10f8:c487 bus 1 dev 4 serial X", empty when none

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::atomic<SourceState> state_{SourceState::starting};
};

}  // namespace naneye::driver
