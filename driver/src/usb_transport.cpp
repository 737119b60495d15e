#include "naneye/driver/usb_transport.hpp"

#include <libusb.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <mutex>
#include <thread>
#include <vector>

#include "log.hpp"
#include "naneye/base/clock.hpp"
#include "usb_open.hpp"

namespace naneye::driver {
namespace {

using Clock = std::chrono::steady_clock;
using base::monotonic_ns;

// After a hotplug arrival: up to 5 tries 50 ms apart (250 ms, a few times udev's usual rule run and
// a short bring-up) before the ordinary backoff takes over again.
constexpr int kSettleTries = 5;
constexpr std::chrono::milliseconds kSettleDelay{50};

}  // namespace

struct UsbTransport::Impl {
  struct Slot {
    Impl* owner = nullptr;
    libusb_transfer* transfer = nullptr;
    std::vector<unsigned char> buffer;
    bool active = false;
  };

  UsbTransportSettings s;
  UsbTransportSink& sink;
  std::atomic<SourceState>& state;
  libusb_context* ctx = nullptr;
  libusb_device_handle* handle = nullptr;
  libusb_device* device = nullptr;  // of `handle`, to recognise its hotplug departure
  libusb_hotplug_callback_handle hotplug = 0;
  bool has_hotplug = false;
  std::thread thread;
  std::atomic<bool> stopping{false};
  std::atomic<bool> arrived{false};
  // Tries left at the short settle delay after an arrival: udev applies the node's permissions and
  // a bring-up may still be running when the event comes, so the first open or claim can fail.
  int settle_tries = 0;
  std::vector<Slot> slots;
  int active = 0;
  bool lost = false;        // the board went away: drop it and wait for it
  bool broken = false;      // it misbehaves: close and reopen it
  bool clear_halt = false;  // the endpoint stalled
  int consecutive_errors = 0;
  std::int64_t last_data_ns = 0;
  std::string last_why;  // why the last connection attempt failed
  std::atomic<std::uint64_t> bytes{0}, transfers{0}, errors{0}, stalls{0};
  mutable std::mutex desc_mutex;
  std::string desc;
  base::Backoff backoff;  // connects = its successes, reconnects = its recoveries

  Impl(UsbTransportSettings settings, UsbTransportSink& k, std::atomic<SourceState>& st)
      : s(std::move(settings)), sink(k), state(st), backoff(s.backoff, log(), "usb") {}

  void set_state(SourceState st) {
    if (state.exchange(st) != st) sink.on_state(st);
  }

  void pump(std::chrono::milliseconds timeout) {
    timeval tv{static_cast<time_t>(timeout.count() / 1000),
               static_cast<suseconds_t>(timeout.count() % 1000 * 1000)};
    libusb_handle_events_timeout_completed(ctx, &tv, nullptr);
  }

  static void LIBUSB_CALL on_transfer(libusb_transfer* t) {
    auto* slot = static_cast<Slot*>(t->user_data);
    slot->owner->completed(*slot);
  }

  static int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device* dev, libusb_hotplug_event ev,
                                    void* self) {
    auto* impl = static_cast<Impl*>(self);
    if (ev == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) impl->arrived = true;
    if (ev == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT && dev == impl->device) impl->lost = true;
    return 0;
  }

  bool submit(Slot& slot) {
    libusb_fill_bulk_transfer(slot.transfer, handle, s.profile.endpoint, slot.buffer.data(),
                              static_cast<int>(slot.buffer.size()), &Impl::on_transfer, &slot, 0);
    const int r = libusb_submit_transfer(slot.transfer);
    if (r == 0) {
      slot.active = true;
      ++active;
      return true;
    }
    if (r == LIBUSB_ERROR_NO_DEVICE) {
      lost = true;
    } else {
      ++errors;
      broken = true;
      log()->warn("usb: cannot submit a transfer: {}", libusb_strerror(r));
    }
    return false;
  }

  void completed(Slot& slot) {
    slot.active = false;
    --active;
    libusb_transfer* t = slot.transfer;
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
      case LIBUSB_TRANSFER_TIMED_OUT:
        consecutive_errors = 0;
        if (t->actual_length > 0) {
          last_data_ns = monotonic_ns();
          bytes += static_cast<std::uint64_t>(t->actual_length);
          ++transfers;
          if (state.load() == SourceState::stalled) set_state(SourceState::streaming);
          sink.on_bytes({t->buffer, static_cast<std::size_t>(t->actual_length)}, last_data_ns);
        }
        break;
      case LIBUSB_TRANSFER_CANCELLED:
        return;
      case LIBUSB_TRANSFER_NO_DEVICE:
        lost = true;
        return;
      case LIBUSB_TRANSFER_STALL:
        ++errors;
        clear_halt = true;
        sink.on_discontinuity();
        return;
      default:  // LIBUSB_TRANSFER_ERROR, LIBUSB_TRANSFER_OVERFLOW: bytes were lost
        ++errors;
        sink.on_discontinuity();
        if (++consecutive_errors > 2 * s.profile.transfer_count) broken = true;
        break;
    }
    if (!stopping && !lost && !broken && !clear_halt) submit(slot);
  }

  bool connect() {
    usb_detail::Found dev = usb_detail::open_matching(ctx, s.profile, s.serial, last_why);
    if (!dev.handle) return false;
    auto fail = [&](const std::string& why) {
      last_why = why;
      libusb_close(dev.handle);
      return false;
    };
    const std::string what = usb_detail::describe(s.profile, dev);
    if (!s.profile.bringup_command.empty()) {
      if (const int rc = usb_detail::run_bringup_command(s.profile.bringup_command, s.profile, dev); rc != 0)
        return fail(what + ": bring-up command exited with " + std::to_string(rc));
    }
    if (s.bringup && !s.bringup(dev.handle)) return fail(what + ": bring-up hook failed");
    libusb_set_auto_detach_kernel_driver(dev.handle, 1);
    if (const int r = libusb_claim_interface(dev.handle, s.profile.interface); r != 0)
      return fail(what + ": cannot claim interface " + std::to_string(s.profile.interface) + ": " +
                  libusb_strerror(r));
    if (s.profile.alt_setting >= 0)
      libusb_set_interface_alt_setting(dev.handle, s.profile.interface, s.profile.alt_setting);
    libusb_clear_halt(dev.handle, s.profile.endpoint);
    for (const auto& c : s.profile.start_controls) {
      auto data = c.data;
      const int r = libusb_control_transfer(dev.handle, c.request_type, c.request, c.value, c.index,
                                            data.data(), static_cast<std::uint16_t>(data.size()), 1000);
      if (r < 0) {
        libusb_release_interface(dev.handle, s.profile.interface);
        return fail(what + ": start control transfer 0x" + fmt::format("{:02x}", c.request) +
                    " failed: " + libusb_strerror(r));
      }
    }
    handle = dev.handle;
    device = libusb_get_device(handle);
    lost = broken = clear_halt = false;
    consecutive_errors = 0;
    for (auto& slot : slots) submit(slot);
    if (lost || broken) {
      drop();
      last_why = what + ": first submissions failed";
      return false;
    }
    {
      std::lock_guard lock(desc_mutex);
      desc = what;
    }
    backoff.succeeded();
    backoff.reset();
    last_data_ns = monotonic_ns();
    log()->info("usb: streaming from {} endpoint 0x{:02x}, {} x {} B transfers", what, s.profile.endpoint,
                slots.size(), s.profile.transfer_size);
    set_state(SourceState::streaming);
    return true;
  }

  // Cancels what is in flight and waits for every callback: libusb must not touch a buffer we free.
  void drain() {
    for (auto& slot : slots)
      if (slot.active) libusb_cancel_transfer(slot.transfer);
    const auto deadline = Clock::now() + s.cancel_timeout;
    while (active > 0 && Clock::now() < deadline) pump(std::chrono::milliseconds(10));
    if (active > 0) log()->error("usb: {} transfers did not complete after cancellation", active);
  }

  // Gives the board back; the caller says why (Backoff::lost), or is stopping.
  void drop() {
    drain();
    sink.on_discontinuity();  // the record in flight is cut
    libusb_release_interface(handle, s.profile.interface);
    libusb_close(handle);
    handle = nullptr;
    device = nullptr;
    {
      std::lock_guard lock(desc_mutex);
      desc.clear();
    }
  }

  void run() {
    auto next_try = Clock::now();
    while (!stopping) {
      if (!handle) {
        set_state(SourceState::waiting_for_device);
        if (arrived.exchange(false)) {
          next_try = Clock::now();
          settle_tries = kSettleTries;
        }
        if (Clock::now() >= next_try) {
          if (connect()) {
            settle_tries = 0;
            continue;
          }
          auto delay = backoff.failed(last_why);
          if (settle_tries > 0) {
            --settle_tries;
            delay = std::min(delay, kSettleDelay);
          }
          next_try = Clock::now() + delay;
        }
        const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next_try - Clock::now());
        pump(std::clamp(wait, std::chrono::milliseconds(1), std::chrono::milliseconds(100)));
        continue;
      }
      pump(std::chrono::milliseconds(50));
      if (stopping) break;
      // A stalled endpoint is cleared in place once its transfers are back: not a reconnect.
      if (clear_halt && active == 0 && !lost && !broken) {
        libusb_clear_halt(handle, s.profile.endpoint);
        clear_halt = false;
        for (auto& slot : slots)
          if (!slot.active) submit(slot);
      }
      if (lost || broken || active == 0) {
        const char* why = lost ? "board lost" : "transfers failing";
        drop();
        next_try = Clock::now() + backoff.lost(why);
        continue;
      }
      const auto idle = std::chrono::nanoseconds(monotonic_ns() - last_data_ns);
      if (state.load() == SourceState::streaming && idle > s.stall_timeout) {
        ++stalls;
        log()->warn("usb: no data for {} ms: stalled",
                    std::chrono::duration_cast<std::chrono::milliseconds>(idle).count());
        set_state(SourceState::stalled);
      }
    }
    if (handle) drop();
  }
};

UsbTransport::UsbTransport(UsbTransportSettings settings, UsbTransportSink& sink)
    : impl_(std::make_unique<Impl>(std::move(settings), sink, state_)) {}

UsbTransport::~UsbTransport() {
  stop();
}

void UsbTransport::start() {
  Impl& m = *impl_;
  if (m.thread.joinable()) return;
  if (const int r = libusb_init(&m.ctx); r != 0)
    throw SourceError(std::string("libusb_init: ") + libusb_strerror(r));
  m.slots.resize(static_cast<std::size_t>(m.s.profile.transfer_count));
  for (auto& slot : m.slots) {
    slot.owner = &m;
    slot.buffer.resize(static_cast<std::size_t>(m.s.profile.transfer_size));
    slot.transfer = libusb_alloc_transfer(0);
  }
  m.has_hotplug = libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) != 0;
  if (m.has_hotplug && libusb_hotplug_register_callback(
                           m.ctx, LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT,
                           LIBUSB_HOTPLUG_NO_FLAGS, m.s.profile.vid, m.s.profile.pid,
                           LIBUSB_HOTPLUG_MATCH_ANY, &Impl::on_hotplug, &m, &m.hotplug) != 0)
    m.has_hotplug = false;  // polling alone still finds the board
  state_ = SourceState::starting;
  m.stopping = false;
  m.thread = std::thread([&m] { m.run(); });
}

void UsbTransport::stop() {
  Impl& m = *impl_;
  if (!m.thread.joinable()) return;
  m.stopping = true;
  libusb_interrupt_event_handler(m.ctx);
  m.thread.join();
  if (m.has_hotplug) libusb_hotplug_deregister_callback(m.ctx, m.hotplug);
  for (auto& slot : m.slots) libusb_free_transfer(slot.transfer);
  m.slots.clear();
  libusb_exit(m.ctx);
  m.ctx = nullptr;
  m.set_state(SourceState::stopped);
}

UsbTransportCounters UsbTransport::counters() const {
  const Impl& m = *impl_;
  const auto b = m.backoff.counters();
  return {m.bytes.load(), m.transfers.load(), m.errors.load(), b.recoveries, m.stalls.load(), b.successes};
}

std::string UsbTransport::device_description() const {
  std::lock_guard lock(impl_->desc_mutex);
  return impl_->desc;
}

}  // namespace naneye::driver
