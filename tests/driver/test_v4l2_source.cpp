// The v4l2:// source against an emulated capture node: every layout and format delivered bit-exact,
// alternate-frame pairing, device loss and return.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <chrono>
#include <thread>

#include "naneye/driver/v4l2_source.hpp"
#include "v4l2_emulator.hpp"

using namespace naneye::driver;
using naneye::test::V4l2DeviceSpec;
using naneye::test::V4l2Emulator;
using naneye::test::V4l2Frame;

namespace {

// A 10-bit test value per pixel, different for each eye and frame.
std::uint16_t pattern(int eye, int frame, int r, int c) {
  return static_cast<std::uint16_t>((r * 7 + c * 3 + eye * 101 + frame * 13) % 1024);
}

// What the source must deliver for `pattern` after the format's round trip.
std::uint16_t expected(V4l2Format f, std::uint16_t v10) {
  if (f == V4l2Format::grey) {
    const int v8 = v10 >> 2;
    return static_cast<std::uint16_t>(v8 << 2 | v8 >> 6);
  }
  return v10;
}

void put(std::vector<std::uint8_t>& img, std::size_t at, V4l2Format f, std::uint16_t v10) {
  switch (f) {
    case V4l2Format::grey:
      img[at] = static_cast<std::uint8_t>(v10 >> 2);
      break;
    case V4l2Format::y16: {
      const std::uint16_t v = static_cast<std::uint16_t>(v10 << 6 | 0x2A);  // low bits must be dropped
      img[at] = static_cast<std::uint8_t>(v & 0xFF);
      img[at + 1] = static_cast<std::uint8_t>(v >> 8);
      break;
    }
    default:
      img[at] = static_cast<std::uint8_t>(v10 & 0xFF);
      img[at + 1] = static_cast<std::uint8_t>(v10 >> 8 | 0xFC);  // bits 10..15 set: must be masked
  }
}

V4l2Frame make_frame(V4l2Layout layout, V4l2Format f, int frame, std::int64_t ts_ns, int only_eye = -1) {
  int w = 0, h = 0;
  layout_size(layout, w, h);
  const std::size_t bpp = static_cast<std::size_t>(bytes_per_pixel(f));
  V4l2Frame out;
  out.image.assign(static_cast<std::size_t>(w * h) * bpp, 0);
  out.timestamp_ns = ts_ns;
  for (int eye = 0; eye < 2; ++eye) {
    if (only_eye >= 0 && eye != only_eye) continue;
    const int x0 = layout == V4l2Layout::side_by_side ? eye * kSensorSize : 0;
    const int y0 = layout == V4l2Layout::top_bottom ? eye * kSensorSize : 0;
    for (int r = 0; r < kSensorSize; ++r)
      for (int c = 0; c < kSensorSize; ++c)
        put(out.image,
            (static_cast<std::size_t>(y0 + r) * static_cast<std::size_t>(w) +
             static_cast<std::size_t>(x0 + c)) *
                bpp,
            f, pattern(eye, frame, r, c));
  }
  return out;
}

::testing::AssertionResult frame_matches(const Frame& fr, V4l2Format f, int eye, int frame) {
  for (int r = 0; r < kSensorSize; ++r)
    for (int c = 0; c < kSensorSize; ++c)
      if (fr.at(r, c) != expected(f, pattern(eye, frame, r, c)))
        return ::testing::AssertionFailure()
               << "eye " << eye << " frame " << frame << " pixel (" << r << "," << c << ") = " << fr.at(r, c)
               << ", want " << expected(f, pattern(eye, frame, r, c));
  return ::testing::AssertionSuccess();
}

V4l2Settings fast_settings(V4l2Layout l, std::optional<V4l2Format> f) {
  V4l2Settings s;
  s.layout = l;
  s.format = f;
  s.poll_timeout = std::chrono::milliseconds(20);
  s.backoff.initial_ms = 10;
  s.backoff.max_ms = 100;
  s.ring_size = 16;
  s.pool_size = 20;
  return s;
}

constexpr std::int64_t kPeriodNs = 22'700'000;

// A node offering `formats` (at the spec's default size unless given) plugged with `frames`, and a
// started source of `s` reading it.
std::unique_ptr<FrameSource> plug_and_start(V4l2Emulator& emu, std::deque<V4l2Frame> frames,
                                            const V4l2Settings& s,
                                            std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_Y10},
                                            std::uint32_t width = 0, std::uint32_t height = 0) {
  V4l2DeviceSpec spec;
  spec.formats = std::move(formats);
  if (width) spec.width = width;
  if (height) spec.height = height;
  emu.plug(spec, std::move(frames));
  auto src = make_v4l2_source(s);
  src->start();
  return src;
}

// Waits up to 5 s for the source to reach `state`.
void wait_for(const FrameSource& src, SourceState state) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (src.state() != state && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

}  // namespace

class V4l2Formats : public ::testing::TestWithParam<std::tuple<V4l2Layout, V4l2Format>> {};

TEST_P(V4l2Formats, EveryPairArrivesBitExactWithBufferTimestamps) {
  const auto [layout, format] = GetParam();
  V4l2Emulator emu;
  int w = 0, h = 0;
  layout_size(layout, w, h);
  std::deque<V4l2Frame> frames;
  for (int i = 0; i < 6; ++i) frames.push_back(make_frame(layout, format, i, 1'000'000'000 + i * kPeriodNs));
  auto src = plug_and_start(emu, std::move(frames), fast_settings(layout, format),
                            {V4L2_PIX_FMT_YUYV, fourcc(format)}, static_cast<std::uint32_t>(w),
                            static_cast<std::uint32_t>(h));
  for (int i = 0; i < 6; ++i) {
    PairPtr p = src->next(std::chrono::seconds(5));
    ASSERT_TRUE(p) << "pair " << i;
    EXPECT_EQ(p->index, static_cast<std::uint64_t>(i));
    EXPECT_TRUE(frame_matches(p->left, format, 0, i));
    EXPECT_TRUE(frame_matches(p->right, format, 1, i));
    EXPECT_EQ(p->left.sensor_ns, 1'000'000'000 + i * kPeriodNs);
    EXPECT_EQ(p->offset_ns(), 0);
    EXPECT_EQ(p->left.color, format == V4l2Format::sgrbg10 ? ColorMode::bayer_grbg : ColorMode::mono);
    EXPECT_EQ(p->left.ticks64, static_cast<std::uint64_t>(i * kPeriodNs) * 48 / 1000);
  }
  EXPECT_EQ(emu.chosen_format(), fourcc(format));
  const auto c = src->counters();
  EXPECT_EQ(c.records, 12u);
  EXPECT_EQ(c.pairs, 6u);
  EXPECT_EQ(c.seq_gaps, 0u);
  src->stop();
  EXPECT_EQ(src->state(), SourceState::stopped);
  EXPECT_FALSE(emu.streaming());
}

INSTANTIATE_TEST_SUITE_P(LayoutsAndFormats, V4l2Formats,
                         ::testing::Combine(::testing::Values(V4l2Layout::side_by_side,
                                                              V4l2Layout::top_bottom),
                                            ::testing::Values(V4l2Format::y10, V4l2Format::y16,
                                                              V4l2Format::grey, V4l2Format::sgrbg10)));

TEST(V4l2Source, AlternateFieldsPairByNearestTimestamp) {
  for (auto format : {V4l2Format::y10, V4l2Format::y16, V4l2Format::grey, V4l2Format::sgrbg10}) {
    V4l2Emulator emu;
    std::deque<V4l2Frame> frames;
    for (int i = 0; i < 4; ++i) {
      for (int eye = 0; eye < 2; ++eye) {
        // One eye per buffer; the right sensor free-runs 4 ms after the left one.
        V4l2Frame f = make_frame(V4l2Layout::alternate, format, i, i * kPeriodNs + eye * 4'000'000, eye);
        f.field = eye == 0 ? V4L2_FIELD_TOP : V4L2_FIELD_BOTTOM;
        frames.push_back(std::move(f));
      }
    }
    auto src = plug_and_start(emu, std::move(frames), fast_settings(V4l2Layout::alternate, format),
                              {fourcc(format)}, 250, 250);
    for (int i = 0; i < 4; ++i) {
      PairPtr p = src->next(std::chrono::seconds(5));
      ASSERT_TRUE(p) << to_string(format) << " pair " << i;
      EXPECT_TRUE(frame_matches(p->left, format, 0, i)) << to_string(format);
      EXPECT_TRUE(frame_matches(p->right, format, 1, i)) << to_string(format);
      EXPECT_EQ(p->offset_ns(), 4'000'000);
    }
    EXPECT_EQ(src->counters().unpaired, 0u);
  }
}

TEST(V4l2Source, AlternateBySequenceParityCountsUnpaired) {
  V4l2Emulator emu;
  std::deque<V4l2Frame> frames;
  // Field NONE, so sequence parity decides the eye: 0 L + 1 R pair; 3 R comes 30 ms after 2 L and
  // 4 L 30 ms after 3 R, so 2 and 3 find no partner (unpaired = 2); 4 L + 5 R pair.
  const std::int64_t ts[] = {0, 3'000'000, 22'700'000, 52'700'000, 82'700'000, 85'000'000};
  for (int i = 0; i < 6; ++i)
    frames.push_back(make_frame(V4l2Layout::alternate, V4l2Format::y10, i, ts[i], 0));
  auto src = plug_and_start(emu, std::move(frames), fast_settings(V4l2Layout::alternate, V4l2Format::y10),
                            {V4L2_PIX_FMT_Y10}, 250, 250);
  PairPtr a = src->next(std::chrono::seconds(5));
  PairPtr b = src->next(std::chrono::seconds(5));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->offset_ns(), 3'000'000);
  EXPECT_EQ(b->left.sensor_ns, 82'700'000);
  EXPECT_EQ(b->right.sensor_ns, 85'000'000);
  EXPECT_TRUE(frame_matches(b->left, V4l2Format::y10, 0, 4));
  EXPECT_EQ(src->counters().unpaired, 2u);
  EXPECT_EQ(src->counters().records, 6u);
}

TEST(V4l2Source, DeviceLossWaitsAndResumes) {
  V4l2Emulator emu;
  V4l2DeviceSpec spec;
  spec.formats = {V4L2_PIX_FMT_Y10};
  auto batch = [](int from) {
    std::deque<V4l2Frame> f;
    for (int i = from; i < from + 4; ++i)
      f.push_back(make_frame(V4l2Layout::side_by_side, V4l2Format::y10, i, i * kPeriodNs));
    return f;
  };
  emu.plug(spec, batch(0));
  emu.unplug_after(4);
  auto src = make_v4l2_source(fast_settings(V4l2Layout::side_by_side, V4l2Format::y10));
  src->start();
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(src->next(std::chrono::seconds(5)));
  wait_for(*src, SourceState::waiting_for_device);
  ASSERT_EQ(src->state(), SourceState::waiting_for_device);
  EXPECT_TRUE(emu.unplugged());
  std::this_thread::sleep_for(std::chrono::milliseconds(60));  // a few failed attempts on the missing node
  emu.plug(spec, batch(4));
  for (int i = 4; i < 8; ++i) {
    PairPtr p = src->next(std::chrono::seconds(5));
    ASSERT_TRUE(p) << i;
    EXPECT_TRUE(frame_matches(p->left, V4l2Format::y10, 0, i));
  }
  EXPECT_EQ(src->state(), SourceState::streaming);
  const auto c = src->counters();
  EXPECT_EQ(c.reconnects, 1u);
  EXPECT_EQ(c.pairs, 8u);
  EXPECT_EQ(c.transfer_errors, 0u);
}

TEST(V4l2Source, RefusesAFormatTheDeviceLacks) {
  V4l2Emulator emu;
  V4l2DeviceSpec spec;
  spec.formats = {V4L2_PIX_FMT_YUYV};
  emu.plug(spec, {});
  auto src = make_v4l2_source(fast_settings(V4l2Layout::side_by_side, V4l2Format::y10));
  try {
    src->start();
    FAIL() << "start() accepted a format the device does not offer";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("Y10"), std::string::npos) << e.what();
  }
  EXPECT_EQ(src->state(), SourceState::failed);
  EXPECT_TRUE(src->error().has_value());
  EXPECT_FALSE(src->next(std::chrono::milliseconds(0)));
}

TEST(V4l2Source, RefusesALayoutOfTheWrongSize) {
  V4l2Emulator emu;
  V4l2DeviceSpec spec;  // 500 x 250
  spec.formats = {V4L2_PIX_FMT_Y10};
  emu.plug(spec, {});
  auto src = make_v4l2_source(fast_settings(V4l2Layout::top_bottom, V4l2Format::y10));
  try {
    src->start();
    FAIL() << "start() accepted 500x250 for top-bottom";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("250x500"), std::string::npos) << e.what();
  }
}

TEST(V4l2Source, NoFrameForTheStallTimeoutIsAStall) {
  V4l2Emulator emu;
  std::deque<V4l2Frame> frames;
  frames.push_back(make_frame(V4l2Layout::side_by_side, V4l2Format::y10, 0, 0));
  V4l2Frame damaged = make_frame(V4l2Layout::side_by_side, V4l2Format::y10, 1, kPeriodNs);
  damaged.error = true;
  frames.push_back(std::move(damaged));
  auto s = fast_settings(V4l2Layout::side_by_side, std::nullopt);  // format picked from ENUM_FMT
  s.stall_timeout = std::chrono::milliseconds(150);
  auto src = plug_and_start(emu, std::move(frames), s);
  ASSERT_TRUE(src->next(std::chrono::seconds(5)));
  wait_for(*src, SourceState::stalled);
  EXPECT_EQ(src->state(), SourceState::stalled);
  const auto c = src->counters();
  EXPECT_EQ(c.stalls, 1u);
  EXPECT_EQ(c.cut_records, 2u);  // both eyes of the flagged buffer
  EXPECT_EQ(c.pairs, 1u);
  EXPECT_EQ(emu.chosen_format(), fourcc(V4l2Format::y10));
}

namespace {

// Writes the spec's reference pixels into one eye of a side-by-side Y10 frame: row 0 px 0..3 black,
// white, black, white and row 249 px 246 black, 247 white; `good = false` whitens px 246.
void set_reference(V4l2Frame& fr, int eye, bool good) {
  const std::size_t w = 2 * kSensorSize, x0 = static_cast<std::size_t>(eye) * kSensorSize;
  const auto at = [&](std::size_t r, std::size_t c) { return (r * w + x0 + c) * 2; };
  const std::uint16_t black = 20, white = 1000;
  for (std::size_t c = 0; c < 4; ++c) put(fr.image, at(0, c), V4l2Format::y10, c % 2 ? white : black);
  put(fr.image, at(249, 246), V4l2Format::y10, good ? black : white);
  put(fr.image, at(249, 247), V4l2Format::y10, white);
}

// Three side-by-side Y10 frames whose reference pixels pass, except frame 1's right eye.
std::deque<V4l2Frame> frames_with_reference() {
  std::deque<V4l2Frame> frames;
  for (int i = 0; i < 3; ++i) {
    frames.push_back(make_frame(V4l2Layout::side_by_side, V4l2Format::y10, i, i * kPeriodNs));
    set_reference(frames.back(), 0, true);
    set_reference(frames.back(), 1, i != 1);
  }
  return frames;
}

V4l2Settings from_uri(const std::string& uri) {
  auto s = v4l2_settings_from(parse_v4l2_uri(parse_uri(uri)));
  const auto fast = fast_settings(s.layout, s.format);
  s.poll_timeout = fast.poll_timeout;
  s.ring_size = fast.ring_size;
  s.pool_size = fast.pool_size;
  return s;
}

}  // namespace

TEST(V4l2Source, ReferencePixelsAreNotCheckedUnlessTheUriSaysTheGrabberCarriesThem) {
  // Every V4L2 frame was marked reference_ok = true without a look at its pixels, even frame 1,
  // whose right eye fails the check.
  V4l2Emulator emu;
  auto src = plug_and_start(emu, frames_with_reference(), from_uri("v4l2:///dev/video0?format=Y10"));
  for (int i = 0; i < 3; ++i) {
    PairPtr p = src->next(std::chrono::seconds(5));
    ASSERT_TRUE(p) << i;
    EXPECT_EQ(p->left.reference, ReferenceStatus::not_checked) << i;
    EXPECT_EQ(p->right.reference, ReferenceStatus::not_checked) << i;
  }
  EXPECT_EQ(src->counters().reference_unchecked, 6u);
  EXPECT_EQ(src->counters().reference_failures, 0u);
}

TEST(V4l2Source, WithReferenceCheckEachEyeSaysPassedOrFailed) {
  V4l2Emulator emu;
  auto src =
      plug_and_start(emu, frames_with_reference(), from_uri("v4l2:///dev/video0?format=Y10&reference=check"));
  const ReferenceStatus want_right[] = {ReferenceStatus::passed, ReferenceStatus::failed,
                                        ReferenceStatus::passed};
  for (int i = 0; i < 3; ++i) {
    PairPtr p = src->next(std::chrono::seconds(5));
    ASSERT_TRUE(p) << i;
    EXPECT_EQ(p->left.reference, ReferenceStatus::passed) << i;
    EXPECT_EQ(p->right.reference, want_right[i]) << i;
  }
  EXPECT_EQ(src->counters().reference_failures, 1u);
  EXPECT_EQ(src->counters().reference_unchecked, 0u);
}

TEST(V4l2Source, WithReferenceRejectAFailingPairIsNotDelivered) {
  V4l2Emulator emu;
  auto src = plug_and_start(emu, frames_with_reference(),
                            from_uri("v4l2:///dev/video0?format=Y10&reference=reject"));
  PairPtr a = src->next(std::chrono::seconds(5));
  PairPtr b = src->next(std::chrono::seconds(5));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->left.sensor_ns, 0);
  EXPECT_EQ(b->left.sensor_ns, 2 * kPeriodNs);  // frame 1 was refused
  EXPECT_EQ(b->right.reference, ReferenceStatus::passed);
  EXPECT_EQ(src->counters().reference_failures, 1u);
  EXPECT_EQ(src->counters().pairs, 2u);
}
