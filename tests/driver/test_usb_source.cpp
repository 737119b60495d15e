// usb:// end to end on the emulated board: a capture crafted with encode_record streams through a
// ring of bulk transfers into bit-exact pairs; unplug mid-record and replug; stop with URBs in flight.
#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <thread>

#include "../support/wait_until.hpp"
#include "naneye/driver/source_registry.hpp"
#include "naneye/driver/usb_source.hpp"
#include "naneye/driver/wire_format.hpp"
#include "usb_emulator.hpp"

using namespace naneye::driver;
using naneye::test::UsbDeviceSpec;
using naneye::test::UsbEmulator;

namespace {

constexpr std::uint32_t kPeriodTicks = 1'089'600;  // 22.7 ms at 48 MHz
constexpr std::uint32_t kRightLagTicks = 144'000;  // the right sensor runs 3 ms behind

std::uint16_t pixel(int sensor, int record, int r, int c) {
  // Reference pixels (spec): row 0 cols 0..3 black, black... kept within the check's thresholds.
  if (r == 0 && c < 4) return (c % 2 == 0) ? 40 : 1000;
  if (r == kSensorSize - 1 && c == 246) return 30;
  if (r == kSensorSize - 1 && c == 247) return 990;
  return static_cast<std::uint16_t>((r * 5 + c * 11 + sensor * 333 + record * 17) % 1024);
}

// Records seq0.. alternating left, right; record k belongs to frame k / 2.
std::vector<std::uint8_t> capture(int records, int first_seq, std::uint32_t t0) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(records) * kRecordSize);
  std::vector<std::uint16_t> px(kPixelCount);
  for (int k = 0; k < records; ++k) {
    const int sensor = k % 2;
    for (int r = 0; r < kSensorSize; ++r)
      for (int c = 0; c < kSensorSize; ++c)
        px[static_cast<std::size_t>(r * kSensorSize + c)] = pixel(sensor, first_seq + k, r, c);
    RecordHeader h;
    h.seq = static_cast<std::uint8_t>(first_seq + k);
    h.sensor = sensor ? Sensor::right : Sensor::left;
    h.ticks = t0 + static_cast<std::uint32_t>(k / 2) * kPeriodTicks + (sensor ? kRightLagTicks : 0);
    encode_record(h, std::span<const std::uint16_t, kPixelCount>(px),
                  std::span<std::uint8_t, kRecordSize>(out.data() + static_cast<std::size_t>(k) * kRecordSize,
                                                       kRecordSize));
  }
  return out;
}

::testing::AssertionResult same_pixels(const Frame& f, int sensor, int record) {
  for (int r = 0; r < kSensorSize; ++r)
    for (int c = 0; c < kSensorSize; ++c)
      if (f.at(r, c) != pixel(sensor, record, r, c))
        return ::testing::AssertionFailure()
               << "record " << record << " (" << r << "," << c << ") = " << f.at(r, c) << ", want "
               << pixel(sensor, record, r, c);
  return ::testing::AssertionSuccess();
}

UsbSourceSettings source_settings_for(const UsbDeviceSpec& spec, int count, int size) {
  UsbSourceSettings s;
  s.transport.profile = builtin_usb_profiles().front();
  s.transport.profile.vid = spec.vid;
  s.transport.profile.pid = spec.pid;
  s.transport.profile.transfer_count = count;
  s.transport.profile.transfer_size = size;
  s.transport.backoff.initial_ms = 20;
  s.transport.backoff.max_ms = 200;
  s.stream.ring_capacity = 32;  // room for a whole test capture: a slow (sanitized) reader drops nothing
  return s;
}

using naneye::test::wait_until;

}  // namespace

TEST(UsbSource, StreamsACaptureThroughTheRingBitExact) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, capture(60, 0, 5000));
  auto src = make_usb_source(source_settings_for(spec, 8, 128 * 1024));
  src->start();
  for (int i = 0; i < 30; ++i) {
    PairPtr p = src->next(std::chrono::seconds(10));
    ASSERT_TRUE(p) << "pair " << i << " state " << to_string(src->state());
    EXPECT_EQ(p->index, static_cast<std::uint64_t>(i));
    EXPECT_EQ(p->left.seq, 2 * i);
    EXPECT_EQ(p->right.seq, 2 * i + 1);
    EXPECT_TRUE(same_pixels(p->left, 0, 2 * i));
    EXPECT_TRUE(same_pixels(p->right, 1, 2 * i + 1));
    EXPECT_EQ(p->offset_ns(), 3'000'000);
    EXPECT_EQ(p->left.reference, naneye::driver::ReferenceStatus::passed);
    EXPECT_EQ(p->right.reference, naneye::driver::ReferenceStatus::passed);
  }
  EXPECT_GE(emu.max_in_flight(), 4u);
  // The base counts a pair just after handing it over: let the last increment land.
  ASSERT_TRUE(wait_until([&] { return src->counters().pairs == 30; }, 2000));
  const auto c = src->counters();
  EXPECT_EQ(c.bytes, 60 * kRecordSize);
  EXPECT_EQ(c.records, 60u);
  EXPECT_EQ(c.pairs, 30u);
  EXPECT_EQ(c.sync_losses + c.seq_gaps + c.cut_records + c.unpaired + c.reconnects + c.transfer_errors, 0u);
  EXPECT_EQ(c.pairs_dropped, 0u);
  EXPECT_EQ(src->state(), SourceState::streaming);
  EXPECT_NE(src->info().device.find("10f8:c487 bus 1 dev 4"), std::string::npos) << src->info().device;
  src->stop();
  EXPECT_EQ(src->state(), SourceState::stopped);
}

TEST(UsbSource, UnplugMidRecordThenReplugReconnects) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, capture(20, 0, 5000));
  emu.unplug_after(10 * kRecordSize + kRecordSize / 2);  // in the middle of record 10
  auto src = make_usb_source(source_settings_for(spec, 8, 64 * 1024));
  src->start();
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(src->next(std::chrono::seconds(10))) << i;
  ASSERT_TRUE(emu.wait_unplugged(10000));
  ASSERT_TRUE(wait_until([&] { return src->state() == SourceState::waiting_for_device; }));
  EXPECT_FALSE(src->next(std::chrono::milliseconds(100)));  // the cut record 10 is never delivered
  EXPECT_EQ(src->counters().cut_records, 1u);

  spec.address = 7;  // replugged: new address
  emu.plug(spec, capture(20, 20, 5000 + 10 * kPeriodTicks));
  for (int i = 0; i < 10; ++i) {
    PairPtr p = src->next(std::chrono::seconds(10));
    ASSERT_TRUE(p) << "after replug, pair " << i;
    EXPECT_TRUE(same_pixels(p->left, 0, 20 + 2 * i));
    EXPECT_TRUE(same_pixels(p->right, 1, 21 + 2 * i));
  }
  EXPECT_EQ(src->state(), SourceState::streaming);
  ASSERT_TRUE(wait_until([&] { return src->counters().pairs == 15; }, 2000)) << src->counters().pairs;
  const auto c = src->counters();
  EXPECT_EQ(c.reconnects, 1u);
  EXPECT_EQ(c.cut_records, 1u);
  EXPECT_EQ(c.records, 30u);
  EXPECT_EQ(c.pairs, 15u);
  EXPECT_EQ(c.sync_losses, 0u);
  EXPECT_NE(src->info().device.find("dev 7"), std::string::npos) << src->info().device;
  src->stop();
}

TEST(UsbSource, StopDiscardsTheTransfersInFlight) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, capture(4, 0, 0));
  auto src = make_usb_source(source_settings_for(spec, 5, 32 * 1024));
  src->start();
  ASSERT_TRUE(src->next(std::chrono::seconds(10)));
  ASSERT_TRUE(src->next(std::chrono::seconds(10)));
  ASSERT_TRUE(wait_until([&] { return emu.in_flight() == 5; }));  // stream over: all wait in the kernel
  src->stop();
  EXPECT_EQ(emu.discarded(), 5u);
  EXPECT_EQ(emu.in_flight(), 0u);
  EXPECT_FALSE(emu.claimed());
  EXPECT_EQ(src->state(), SourceState::stopped);
}

TEST(UsbSource, RegistryOpensUsbAndV4l2Uris) {
  SourceRegistry reg = make_default_registry();
  EXPECT_TRUE(reg.has("usb"));
  EXPECT_TRUE(reg.has("v4l2"));
  auto usb = reg.open("usb://10f8:c482?serial=X1&endpoint=0x82");
  EXPECT_EQ(usb->info().kind, "usb");
  auto v4l2 = reg.open("v4l2:///dev/video3?layout=alternate&format=GREY");
  EXPECT_EQ(v4l2->info().kind, "v4l2");
  EXPECT_THROW(reg.open("v4l2:///dev/video0?layout=diagonal"), SourceError);
}

TEST(UsbSource, UriParametersOverrideTheProfile) {
  const SourceUri uri = parse_uri("usb://10f8:c482?serial=X1&endpoint=0x82");
  const auto s =
      usb_settings_from(uri, parse_usb_uri(uri), std::filesystem::path(NANEYE_SOURCE_DIR) / "config/devices");
  EXPECT_EQ(s.transport.profile.name, "cesys-efm01");
  EXPECT_EQ(s.transport.profile.endpoint, 0x82);
  EXPECT_EQ(s.transport.serial, "X1");
  const SourceUri plain = parse_uri("usb://10f8:c487");
  const auto p = usb_settings_from(plain, parse_usb_uri(plain),
                                   std::filesystem::path(NANEYE_SOURCE_DIR) / "config/devices");
  EXPECT_EQ(p.transport.profile.name, "cesys-nanousb2");
  EXPECT_EQ(p.transport.profile.endpoint, 0x86);
  EXPECT_EQ(p.transport.profile.transfer_count, 8);
  EXPECT_FALSE(p.transport.profile.endpoint_confirmed);
}

TEST(UsbSource, TransferErrorCutsTheRecordAndResyncs) {
  UsbEmulator emu;
  UsbDeviceSpec spec;
  emu.plug(spec, capture(20, 0, 5000));
  // The 40th 16 KiB transfer starts inside record 5 (the right half of frame 2): it fails with a bus
  // error and 100 bytes are lost with it.
  emu.fail_transfer_at(39 * 16384, -EPROTO, 100);
  auto src = make_usb_source(source_settings_for(spec, 4, 16384));
  src->start();
  std::vector<int> left_seqs;
  for (int i = 0; i < 9; ++i) {
    PairPtr p = src->next(std::chrono::seconds(10));
    ASSERT_TRUE(p) << "pair " << i;
    EXPECT_TRUE(same_pixels(p->left, 0, p->left.seq));
    EXPECT_TRUE(same_pixels(p->right, 1, p->right.seq));
    left_seqs.push_back(p->left.seq);
  }
  EXPECT_EQ(left_seqs, (std::vector<int>{0, 2, 6, 8, 10, 12, 14, 16, 18}));
  ASSERT_TRUE(wait_until([&] { return src->counters().pairs == 9; }, 2000));
  const auto c = src->counters();
  EXPECT_EQ(c.transfer_errors, 1u);
  EXPECT_EQ(c.cut_records, 1u);  // record 5
  EXPECT_EQ(c.unpaired, 1u);     // record 4 lost its partner
  EXPECT_EQ(c.records, 19u);     // all but the cut one
  EXPECT_EQ(c.reconnects, 0u);
  EXPECT_EQ(src->state(), SourceState::streaming);
  src->stop();
}
