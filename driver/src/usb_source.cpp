#include "naneye/driver/usb_source.hpp"

#include <fmt/format.h>

#include "log.hpp"
#include "naneye/base/clock.hpp"

namespace naneye::driver {
namespace {

class UsbSource final : public ByteStreamSource, private UsbTransportSink {
 public:
  UsbSource(UsbSourceSettings s, std::string uri)
      : ByteStreamSource(SourceInfo{std::move(uri), "usb", "", true, 44.0}, s.stream),
        transport_(std::move(s.transport), *this) {}
  ~UsbSource() override { stop(); }

  SourceCounters counters() const override {
    SourceCounters c = ByteStreamSource::counters();
    const auto t = transport_.counters();
    c.reconnects += t.reconnects;
    c.transfer_errors += t.transfer_errors;
    c.stalls += t.stalls;
    return c;
  }

  SourceInfo info() const override {
    SourceInfo i = ByteStreamSource::info();
    i.device = transport_.device_description();
    return i;
  }

 private:
  void run() override {
    transport_.start();
    // The transport's event thread does the work; this thread only waits for stop().
    while (sleep_until(std::chrono::steady_clock::now() + std::chrono::seconds(1))) {
    }
    transport_.stop();
  }

  void on_bytes(std::span<const std::uint8_t> bytes, std::int64_t host_ns) override { feed(bytes, host_ns); }
  void on_discontinuity() override { end_of_stream(base::monotonic_ns()); }
  void on_state(SourceState s) override {
    if (s != SourceState::stopped && !stopping()) set_state(s);
  }

  UsbTransport transport_;
};

}  // namespace

UsbSourceSettings usb_settings_from(const SourceUri& uri, const UsbUri& parsed,
                                    const std::filesystem::path& profile_dir) {
  UsbSourceSettings s;
  if (auto p = find_usb_profile(profile_dir, parsed.vid, parsed.pid)) {
    s.transport.profile = std::move(*p);
  } else {
    s.transport.profile.name = fmt::format("generic-{:04x}-{:04x}", parsed.vid, parsed.pid);
    s.transport.profile.label = "no profile: URI parameters only";
    s.transport.profile.vid = parsed.vid;
    s.transport.profile.pid = parsed.pid;
  }
  // Explicit URI parameters win over the profile; defaults of the URI parser do not.
  if (uri.param("interface")) s.transport.profile.interface = parsed.interface;
  if (uri.param("endpoint")) s.transport.profile.endpoint = parsed.endpoint;
  if (parsed.serial) s.transport.serial = *parsed.serial;
  s.stream = parsed.stream;
  return s;
}

std::unique_ptr<FrameSource> make_usb_source(UsbSourceSettings settings, std::string uri) {
  if (uri.empty())
    uri = fmt::format("usb://{:04x}:{:04x}", settings.transport.profile.vid, settings.transport.profile.pid);
  if (settings.transport.profile.transfer_count < 1 || settings.transport.profile.transfer_size < 512)
    throw SourceError("usb: transfer count must be >= 1 and size >= 512");
  return std::make_unique<UsbSource>(std::move(settings), std::move(uri));
}

}  // namespace naneye::driver
