// The libusb transport against the emulated board: ring of bulk transfers, vendor start controls,
// device loss and return, clean stop with transfers in flight.
#include <gtest/gtest.h>

#include <libusb.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>

#include "../support/wait_until.hpp"
#include "naneye/driver/usb_transport.hpp"
#include "usb_emulator.hpp"

using namespace naneye::driver;
using naneye::test::UsbDeviceSpec;
using naneye::test::UsbEmulator;

namespace {

struct CollectingSink : UsbTransportSink {
  std::mutex m;
  std::vector<std::uint8_t> bytes;
  int discontinuities = 0;
  std::vector<SourceState> states;
  void on_bytes(std::span<const std::uint8_t> b, std::int64_t) override {
    std::lock_guard lock(m);
    bytes.insert(bytes.end(), b.begin(), b.end());
  }
  void on_discontinuity() override {
    std::lock_guard lock(m);
    ++discontinuities;
  }
  void on_state(SourceState s) override {
    std::lock_guard lock(m);
    states.push_back(s);
  }
  std::size_t size() {
    std::lock_guard lock(m);
    return bytes.size();
  }
};

std::vector<std::uint8_t> random_bytes(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> v(n);
  for (auto& b : v) b = static_cast<std::uint8_t>(rng());
  return v;
}

using naneye::test::wait_until;

UsbTransportSettings settings_for(const UsbDeviceSpec& spec, int count, int size) {
  UsbTransportSettings s;
  s.profile = builtin_usb_profiles().front();
  s.profile.vid = spec.vid;
  s.profile.pid = spec.pid;
  s.profile.endpoint = spec.endpoint;
  s.profile.transfer_count = count;
  s.profile.transfer_size = size;
  s.backoff.initial_ms = 20;
  s.backoff.max_ms = 200;
  s.stall_timeout = std::chrono::milliseconds(300);
  return s;
}

}  // namespace

TEST(UsbTransport, RingDeliversTheStreamInOrderWithVendorControls) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  const auto stream = random_bytes(3'000'000 + 777, 1);
  emu.plug(spec, stream);
  CollectingSink sink;
  auto s = settings_for(spec, 8, 64 * 1024);
  s.profile.start_controls.push_back({0x40, 0xB1, 0x0102, 0x0003, {0xDE, 0xAD}, "test"});
  UsbTransport t(s, sink);
  t.start();
  ASSERT_TRUE(wait_until([&] { return sink.size() >= stream.size(); })) << sink.size();
  EXPECT_EQ(t.state(), SourceState::streaming);
  t.stop();
  EXPECT_EQ(t.state(), SourceState::stopped);
  ASSERT_EQ(sink.bytes.size(), stream.size());
  EXPECT_TRUE(sink.bytes == stream);
  EXPECT_EQ(emu.max_in_flight(), 8u);
  const auto c = t.counters();
  EXPECT_EQ(c.bytes, stream.size());
  EXPECT_EQ(c.reconnects, 0u);
  EXPECT_EQ(c.connects, 1u);
  const auto controls = emu.vendor_controls();
  ASSERT_EQ(controls.size(), 1u);
  EXPECT_EQ(controls[0].request, 0xB1);
  EXPECT_EQ(controls[0].value, 0x0102);
  EXPECT_EQ(controls[0].index, 0x0003);
  EXPECT_EQ(controls[0].data, (std::vector<std::uint8_t>{0xDE, 0xAD}));
}

TEST(UsbTransport, StopCancelsEveryTransferInFlight) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, random_bytes(100'000, 2));
  CollectingSink sink;
  UsbTransport t(settings_for(spec, 6, 16384), sink);
  t.start();
  // Stream exhausted: all six transfers wait in the emulated kernel.
  ASSERT_TRUE(wait_until([&] { return sink.size() == 100'000 && emu.in_flight() == 6; }));
  t.stop();
  EXPECT_EQ(emu.discarded(), 6u);
  EXPECT_EQ(emu.in_flight(), 0u);
  EXPECT_FALSE(emu.claimed());
}

TEST(UsbTransport, SerialSelectsTheBoard) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  spec.serial = "ABC123";
  emu.plug(spec, random_bytes(10'000, 3));
  CollectingSink wrong_sink;
  auto s = settings_for(spec, 4, 4096);
  s.serial = "OTHER";
  UsbTransport wrong(s, wrong_sink);
  wrong.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(150));
  EXPECT_EQ(wrong.state(), SourceState::waiting_for_device);
  wrong.stop();
  EXPECT_EQ(wrong_sink.size(), 0u);

  CollectingSink sink;
  s.serial = "ABC123";
  UsbTransport right(s, sink);
  right.start();
  ASSERT_TRUE(wait_until([&] { return sink.size() == 10'000; }));
  EXPECT_NE(right.device_description().find("serial ABC123"), std::string::npos);
}

TEST(UsbTransport, NoDataForTheStallTimeoutIsAStall) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, random_bytes(50'000, 4));
  CollectingSink sink;
  UsbTransport t(settings_for(spec, 4, 8192), sink);
  t.start();
  ASSERT_TRUE(wait_until([&] { return t.state() == SourceState::stalled; }, 5000));
  EXPECT_EQ(t.counters().stalls, 1u);
  EXPECT_EQ(sink.size(), 50'000u);
}

TEST(UsbTransport, UnplugAndReplugReconnects) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  const auto first = random_bytes(400'000, 5);
  emu.plug(spec, first);
  emu.unplug_after(250'000);
  CollectingSink sink;
  UsbTransport t(settings_for(spec, 8, 16384), sink);
  t.start();
  ASSERT_TRUE(emu.wait_unplugged(10000));
  ASSERT_TRUE(wait_until([&] { return t.state() == SourceState::waiting_for_device; }));
  EXPECT_EQ(sink.size(), 250'000u);
  EXPECT_GE(sink.discontinuities, 1);
  spec.address = 5;  // a replugged board gets a new address
  const auto second = random_bytes(300'000, 6);
  emu.plug(spec, second);
  ASSERT_TRUE(wait_until([&] { return sink.size() == 550'000u; })) << sink.size();
  t.stop();
  EXPECT_TRUE(std::equal(second.begin(), second.end(), sink.bytes.begin() + 250'000));
  EXPECT_EQ(t.counters().reconnects, 1u);
  EXPECT_EQ(t.counters().connects, 2u);
}

TEST(UsbTransport, HotplugArrivalCutsTheBackoffShort) {
  if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) GTEST_SKIP() << "libusb without hotplug: polling only";
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, random_bytes(20'000, 7));
  emu.unplug_after(20'000);
  CollectingSink sink;
  auto s = settings_for(spec, 4, 4096);
  s.backoff.initial_ms = 20'000;  // polling alone would not retry within the test
  s.backoff.max_ms = s.backoff.initial_ms;
  UsbTransport t(s, sink);
  t.start();
  ASSERT_TRUE(emu.wait_unplugged(10000));
  ASSERT_TRUE(wait_until([&] { return t.state() == SourceState::waiting_for_device; }));
  spec.address = 6;
  emu.plug(spec, random_bytes(10'000, 8));
  ASSERT_TRUE(wait_until([&] { return sink.size() == 30'000; }, 5000)) << "no reconnect on the arrival event";
  EXPECT_EQ(t.counters().reconnects, 1u);
}

// A board that is not ready when its arrival event comes (claim refused twice) is still taken within
// the settle tries, not after the 20 s backoff.
TEST(UsbTransport, ArrivalRetriesAClaimWhileTheBoardSettles) {
  if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) GTEST_SKIP() << "libusb without hotplug: polling only";
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, random_bytes(20'000, 17));
  emu.unplug_after(20'000);
  CollectingSink sink;
  auto s = settings_for(spec, 4, 4096);
  s.backoff.initial_ms = 20'000;
  s.backoff.max_ms = s.backoff.initial_ms;
  UsbTransport t(s, sink);
  t.start();
  ASSERT_TRUE(emu.wait_unplugged(10000));
  ASSERT_TRUE(wait_until([&] { return t.state() == SourceState::waiting_for_device; }));
  emu.refuse_claims(2, EBUSY);
  spec.address = 7;
  emu.plug(spec, random_bytes(10'000, 18));
  ASSERT_TRUE(wait_until([&] { return sink.size() == 30'000; }, 5000)) << "the settle tries gave up";
  EXPECT_EQ(t.counters().reconnects, 1u);
  EXPECT_EQ(emu.claims_refused(), 2);
}

TEST(UsbTransport, EndpointStallIsClearedInPlace) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  const auto stream = random_bytes(200'000, 9);
  emu.plug(spec, stream);
  emu.fail_transfer_at(5 * 8192, -EPIPE, 0);  // the sixth transfer stalls; no bytes are lost
  CollectingSink sink;
  UsbTransport t(settings_for(spec, 4, 8192), sink);
  t.start();
  ASSERT_TRUE(wait_until([&] { return sink.size() == stream.size(); })) << sink.size();
  t.stop();
  EXPECT_TRUE(sink.bytes == stream);
  EXPECT_EQ(sink.discontinuities, 2);  // the stall, then the stop
  EXPECT_EQ(emu.clear_halts(), 2u);    // once at the claim, once after the stall
  const auto c = t.counters();
  EXPECT_EQ(c.transfer_errors, 1u);
  EXPECT_EQ(c.reconnects, 0u);
  EXPECT_EQ(c.connects, 1u);
}

TEST(UsbTransport, BringupCommandRunsWithTheBoardsAddress) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  spec.bus = 3;
  spec.address = 12;
  emu.plug(spec, random_bytes(10'000, 10));
  const std::string out = ::testing::TempDir() + "naneye_bringup_env.txt";
  std::remove(out.c_str());
  CollectingSink sink;
  auto s = settings_for(spec, 4, 4096);
  s.profile.bringup_command =
      "echo $NANEYE_USB_BUS $NANEYE_USB_ADDRESS $NANEYE_USB_VID $NANEYE_USB_PID $NANEYE_USB_SERIAL > " + out;
  UsbTransport t(s, sink);
  t.start();
  ASSERT_TRUE(wait_until([&] { return sink.size() == 10'000; }));
  t.stop();
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "3 12 10f8 c487 NE0001");
}

TEST(UsbTransport, FailingBringupKeepsWaitingWithoutClaiming) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, random_bytes(10'000, 11));
  CollectingSink sink;
  auto s = settings_for(spec, 4, 4096);
  s.profile.bringup_command = "exit 3";
  int hook_calls = 0;
  s.bringup = [&](libusb_device_handle*) { return ++hook_calls, true; };
  UsbTransport t(s, sink);
  t.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(t.state(), SourceState::waiting_for_device);
  EXPECT_FALSE(emu.claimed());
  EXPECT_EQ(hook_calls, 0);  // the command failed first
  t.stop();
  EXPECT_EQ(sink.size(), 0u);
  EXPECT_EQ(t.counters().connects, 0u);
}
