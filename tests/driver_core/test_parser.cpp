// The stream parser on crafted streams: sync acquisition, in-sync delivery, gaps, wraps, corruption,
// truncation, chunking, pixel checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "naneye/driver/stream_parser.hpp"
#include "stream_builder.hpp"

namespace naneye::driver {
namespace {

using test::CollectingSink;
using test::RecordSpec;

struct ParserHarness {
  CollectingSink sink;
  AtomicCounters counters;
  StreamParser parser;
  explicit ParserHarness(const ParserSettings& s = {}) : parser(s, sink, counters) {}
  void feed(std::span<const std::uint8_t> b, std::size_t chunk) {
    for (std::size_t i = 0; i < b.size(); i += chunk)
      parser.feed(b.subspan(i, std::min(chunk, b.size() - i)), 7);
  }
  SourceCounters c() const { return counters.snapshot(); }
};

void expect_frames(const std::vector<Frame>& got, const std::vector<RecordSpec>& want,
                   int size = kSensorSize) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_TRUE(test::frame_matches(got[i], want[i], size)) << "frame " << i;
}

TEST(StreamParser, DeliversEveryRecordOfACleanStreamBitExact) {
  const auto recs = test::alternating(3);
  const auto bytes = test::build(recs);
  ParserHarness r;
  r.feed(bytes, bytes.size());
  r.parser.finish(0);
  expect_frames(r.sink.frames, recs);
  EXPECT_EQ(r.c().records, 6u);
  EXPECT_EQ(r.c().bytes, bytes.size());
  EXPECT_EQ(r.c().sync_losses + r.c().seq_gaps + r.c().cut_records + r.c().corrupt_records, 0u);
  EXPECT_EQ(r.sink.frames[0].reference, ReferenceStatus::passed);
  EXPECT_EQ(r.sink.frames[0].host_ns, 7);
}

TEST(StreamParser, InSyncRecordIsDeliveredWithItsLastByte) {
  const auto recs = test::alternating(2);
  const auto bytes = test::build(recs);
  ParserHarness r;
  r.feed(std::span(bytes).first(3 * kRecordSize - 1), 4096);
  EXPECT_EQ(r.sink.frames.size(), 2u);  // the third record misses one byte
  r.feed(std::span(bytes).subspan(3 * kRecordSize - 1, 1), 1);
  EXPECT_EQ(r.sink.frames.size(), 3u);  // no waiting for the fourth header
  EXPECT_TRUE(test::frame_matches(r.sink.frames[2], recs[2]));
}

TEST(StreamParser, StartsInTheMiddleOfARecord) {
  const auto recs = test::alternating(3);
  const auto bytes = test::build(recs);
  ParserHarness r;
  r.feed(std::span(bytes).subspan(kRecordSize / 2 + 1), 10000);
  r.parser.finish(0);
  expect_frames(r.sink.frames, std::vector<RecordSpec>(recs.begin() + 1, recs.end()));
  EXPECT_EQ(r.c().cut_records, 0u);
}

TEST(StreamParser, OneByteChunksGiveTheSameFrames) {
  const auto recs = test::alternating(2);
  const auto bytes = test::build(recs);
  ParserHarness r;
  r.feed(bytes, 1);
  r.parser.finish(0);
  expect_frames(r.sink.frames, recs);
}

TEST(StreamParser, SplitAtEveryPositionGivesTheSameFrames) {
  constexpr int kSize = 8;
  const auto recs = test::alternating(2);
  const auto bytes = test::build(recs, kSize);
  for (std::size_t cut = 0; cut <= bytes.size(); ++cut) {
    ParserHarness r(test::small_settings(kSize));
    r.parser.feed(std::span(bytes).first(cut), 0);
    r.parser.feed(std::span(bytes).subspan(cut), 0);
    r.parser.finish(0);
    ASSERT_EQ(r.sink.frames.size(), recs.size()) << "split at " << cut;
    for (std::size_t i = 0; i < recs.size(); ++i)
      ASSERT_TRUE(test::frame_matches(r.sink.frames[i], recs[i], kSize));
  }
}

TEST(StreamParser, SeqWrapIsNotAGap) {
  const auto recs = test::alternating(5, 250);  // 250 .. 255, 0 .. 3
  ParserHarness r;
  r.feed(test::build(recs), 65536);
  expect_frames(r.sink.frames, recs);
  EXPECT_EQ(r.c().seq_gaps, 0u);
}

TEST(StreamParser, LostRecordsAreCountedWithoutLosingSync) {
  auto recs = test::alternating(5, 253);           // seq 253 .. 255, 0 .. 6
  recs.erase(recs.begin() + 3, recs.begin() + 6);  // 0, 1, 2 lost across the wrap
  recs.erase(recs.begin() + 4);                    // and 4
  ParserHarness r;
  r.feed(test::build(recs), 16384);
  expect_frames(r.sink.frames, recs);
  EXPECT_EQ(r.c().seq_gaps, 4u);
  EXPECT_EQ(r.c().sync_losses, 0u);
}

TEST(StreamParser, TruncatedTailIsCutNotDelivered) {
  const auto recs = test::alternating(2);
  const auto bytes = test::build(recs);
  for (std::size_t keep : {std::size_t{3}, kHeaderSize, kRecordSize / 2, kRecordSize - 1}) {
    ParserHarness r;
    r.feed(std::span(bytes).first(3 * kRecordSize + keep), 16384);
    r.parser.finish(0);
    expect_frames(r.sink.frames, std::vector<RecordSpec>(recs.begin(), recs.begin() + 3));
    EXPECT_EQ(r.c().cut_records, 1u) << "keeping " << keep;
  }
}

TEST(StreamParser, LoneLastRecordIsConfirmedByItsReferencePixels) {
  auto bytes = test::build({{9, Sensor::right, 5}});
  ParserHarness r;
  r.feed(bytes, 1000);
  EXPECT_TRUE(r.sink.frames.empty());  // no second header yet
  r.parser.finish(0);
  ASSERT_EQ(r.sink.frames.size(), 1u);
  EXPECT_TRUE(test::frame_matches(r.sink.frames[0], {9, Sensor::right, 5}));

  bytes[kHeaderSize + 2] = 0xFF;  // row 0 px 1 (saturated) now 1023 -> still fine; break px 0 instead
  bytes[kHeaderSize + 0] = 0xFF;  // px 0 = 0x3FF: not black
  bytes[kHeaderSize + 1] = 0x03;
  ParserHarness bad;
  bad.feed(bytes, 1000);
  bad.parser.finish(0);
  EXPECT_TRUE(bad.sink.frames.empty());
}

TEST(StreamParser, ReferenceFailureIsCountedAndOptionallyRejected) {
  const auto recs = test::alternating(2);
  auto bytes = test::build(recs);
  const std::size_t last_row = kHeaderSize + 2 * (249 * 250 + 247);  // record 1, row 249 px 247 (white)
  bytes[kRecordSize + last_row] = 10;
  bytes[kRecordSize + last_row + 1] = 0;
  ParserHarness keep;
  keep.feed(bytes, 50000);
  ASSERT_EQ(keep.sink.frames.size(), 4u);
  EXPECT_EQ(keep.sink.frames[1].reference, ReferenceStatus::failed);
  EXPECT_EQ(keep.sink.frames[2].reference, ReferenceStatus::passed);
  EXPECT_EQ(keep.c().reference_failures, 1u);

  ParserSettings s;
  s.reference.reject = true;
  ParserHarness reject(s);
  reject.feed(bytes, 50000);
  EXPECT_EQ(reject.sink.frames.size(), 3u);
  EXPECT_EQ(reject.c().reference_failures, 1u);
  s.reference.white_min = 5;  // thresholds are settings
  ParserHarness lax(s);
  lax.feed(bytes, 50000);
  EXPECT_EQ(lax.sink.frames.size(), 4u);
}

TEST(StreamParser, WithTheCheckOffAFrameSaysNotCheckedNeverPassed) {
  // The bad reference pixel of record 1 goes through unseen, and no frame claims it was checked.
  const auto recs = test::alternating(2);
  auto bytes = test::build(recs);
  bytes[kRecordSize + kHeaderSize + 2 * (249 * 250 + 247)] = 10;
  bytes[kRecordSize + kHeaderSize + 2 * (249 * 250 + 247) + 1] = 0;
  ParserSettings s;
  s.reference.enabled = false;
  ParserHarness off(s);
  off.feed(bytes, 50000);
  ASSERT_EQ(off.sink.frames.size(), 4u);
  for (const auto& f : off.sink.frames) EXPECT_EQ(f.reference, ReferenceStatus::not_checked);
  EXPECT_EQ(off.c().reference_failures, 0u);
  EXPECT_EQ(off.c().reference_unchecked, 4u);
  ParserHarness on;
  on.feed(bytes, 50000);
  EXPECT_EQ(on.c().reference_unchecked, 0u);
}

TEST(StreamParser, OutOfRangePixelsDropTheRecordButNotPadding) {
  const auto recs = test::alternating(2);
  auto bytes = test::build(recs);
  bytes[kRecordSize + kHeaderSize + 2 * 300 + 1] = 0x84;  // record 1, pixel 300: bit 15 set
  const std::size_t pad = 2 * (10 * 250 + 249) + 1;       // record 2, row 10 col 249: padding
  bytes[2 * kRecordSize + kHeaderSize + pad] = 0xF0;
  ParserHarness r;
  r.feed(bytes, 50000);
  ASSERT_EQ(r.sink.frames.size(), 3u);
  EXPECT_EQ(r.sink.frames[1].seq, 2);
  EXPECT_EQ(r.sink.frames[1].at(10, 249) >> 8, 0xF0);  // padding kept as received
  EXPECT_EQ(r.c().corrupt_records, 1u);
  EXPECT_EQ(r.c().sync_losses, 0u);

  ParserSettings s;
  s.reject_out_of_range = false;
  ParserHarness masked(s);
  masked.feed(bytes, 50000);
  ASSERT_EQ(masked.sink.frames.size(), 4u);
  EXPECT_LE(masked.sink.frames[1].pixels[300], kPixelMax);
  EXPECT_EQ(masked.c().corrupt_records, 1u);
}

TEST(StreamParser, BayerFlagIsCarried) {
  ParserSettings s;
  s.color = ColorMode::bayer_grbg;
  ParserHarness r(s);
  r.feed(test::build(test::alternating(1)), 1 << 20);
  ASSERT_EQ(r.sink.frames.size(), 2u);
  EXPECT_EQ(r.sink.frames[0].color, ColorMode::bayer_grbg);
}

TEST(StreamParser, MisplacedHeaderLosesSyncAndReacquires) {
  auto recs = test::alternating(4);
  auto bytes = test::build(recs);
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(2 * kRecordSize + 1000),
              bytes.begin() + static_cast<std::ptrdiff_t>(2 * kRecordSize + 1010));
  ParserHarness r;
  r.feed(bytes, 16384);
  EXPECT_EQ(r.c().sync_losses, 1u);
  // Record 2 lost bytes (dropped as corrupt or delivered damaged), record 3 is lost with the sync,
  // 4 is confirmed by 5, 5..7 follow in sync.
  ASSERT_GE(r.sink.frames.size(), 6u);
  const auto tail = std::vector<Frame>(r.sink.frames.end() - 4, r.sink.frames.end());
  expect_frames(tail, std::vector<RecordSpec>(recs.begin() + 4, recs.end()));
}

// Damage at random places: overwrite, delete or insert up to 64 bytes inside record j. Everything
// from record j + 2 on must come out bit-exact, and nothing from j + 1 on may come out damaged.
void corruption_trials(int size, int trials, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const auto recs = test::alternating(5, static_cast<std::uint8_t>(seed));
  const auto clean = test::build(recs, size);
  const std::size_t rec = clean.size() / recs.size();
  for (int t = 0; t < trials; ++t) {
    auto bytes = clean;
    const std::size_t j = 1 + rng() % 6;
    const std::size_t at = j * rec + rng() % rec;
    const std::size_t len = 1 + rng() % 64;
    const int kind = static_cast<int>(rng() % 3);
    const auto pos = bytes.begin() + static_cast<std::ptrdiff_t>(at);
    if (kind == 0) {
      for (std::size_t k = 0; k < len && at + k < (j + 1) * rec; ++k)
        bytes[at + k] = static_cast<std::uint8_t>(rng());
    } else if (kind == 1) {
      bytes.erase(pos, pos + static_cast<std::ptrdiff_t>(std::min(len, (j + 1) * rec - at)));
    } else {
      std::vector<std::uint8_t> junk(len);
      for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
      bytes.insert(pos, junk.begin(), junk.end());
    }
    ParserHarness r(test::small_settings(size));
    r.feed(bytes, 1 + rng() % 3000);
    r.parser.finish(0);
    std::vector<bool> seen(recs.size(), false);
    for (const Frame& f : r.sink.frames) {
      const auto k = static_cast<std::size_t>(static_cast<std::uint8_t>(f.seq - recs[0].seq));
      ASSERT_LT(k, recs.size());
      if (k != j) {
        ASSERT_TRUE(test::frame_matches(f, recs[k], size))
            << "trial " << t << " kind " << kind << " record " << k;
      }
      seen[k] = true;
    }
    for (std::size_t k = 0; k < recs.size(); ++k) {
      if (k < j || k >= j + 2) {
        ASSERT_TRUE(seen[k]) << "trial " << t << " kind " << kind << " lost record " << k;
      }
    }
  }
}

TEST(StreamParser, BackInSyncWithinTwoRecordsAfterRandomDamage) {
  corruption_trials(16, 200, 1);
}
TEST(StreamParser, BackInSyncWithinTwoRecordsAfterRandomDamageFullSize) {
  corruption_trials(kSensorSize, 12, 2);
}

TEST(StreamParser, JunkBeforeTheFirstHeaderIsSkipped) {
  std::vector<std::uint8_t> bytes(5000);
  std::mt19937 rng(3);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  bytes[100] = 0x07, bytes[101] = 0xB0, bytes[102] = 0xFE, bytes[103] = 0xCA;  // a lone fake header
  const auto recs = test::alternating(2);
  const auto good = test::build(recs);
  bytes.insert(bytes.end(), good.begin(), good.end());
  ParserHarness r;
  r.feed(bytes, 777);
  r.parser.finish(0);
  expect_frames(r.sink.frames, recs);
}

TEST(StreamParser, RefusesImpossibleSensorSizes) {
  CollectingSink sink;
  AtomicCounters c;
  EXPECT_THROW(StreamParser(test::small_settings(3), sink, c), std::invalid_argument);
  EXPECT_THROW(StreamParser(test::small_settings(251), sink, c), std::invalid_argument);
}

}  // namespace
}  // namespace naneye::driver
