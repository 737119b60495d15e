// Pairing left and right records by nearest timestamp: tolerance, order, wraps, unpaired frames.
#include <gtest/gtest.h>

#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pairer.hpp"
#include "stream_builder.hpp"

namespace naneye::driver {
namespace {

using test::RecordSpec;

constexpr int kSize = 8;  // small records: pairing does not look at pixels

struct PoolChannel : PairChannel {
  PairPool pool{16};
  std::vector<PairPtr> pairs;
  PairPtr acquire() override { return pool.try_acquire(); }
  void deliver(PairPtr p) override { pairs.push_back(std::move(p)); }
};

struct Harness {
  PoolChannel channel;
  AtomicCounters counters;
  Pairer pairer;
  StreamParser parser;
  explicit Harness(PairerSettings s = {})
      : pairer(s, channel, counters), parser(test::small_settings(kSize), pairer, counters) {}
  void run(const std::vector<RecordSpec>& recs) {
    const auto bytes = test::build(recs, kSize);
    parser.feed(bytes, 0);
    parser.finish(0);
    pairer.flush();
  }
};

TEST(Pairer, PairsAlternatingRecordsAndKeepsTheOffset) {
  Harness h;
  const auto recs = test::alternating(6, 0, 1000, 1'089'600, 240'000);  // right 5 ms after left
  h.run(recs);
  ASSERT_EQ(h.channel.pairs.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k) {
    const StereoPair& p = *h.channel.pairs[k];
    EXPECT_EQ(p.index, k);
    EXPECT_TRUE(test::frame_matches(p.left, recs[2 * k], kSize));
    EXPECT_TRUE(test::frame_matches(p.right, recs[2 * k + 1], kSize));
    EXPECT_EQ(p.offset_ns(), 5'000'000);
    EXPECT_EQ(p.left.sensor_ns, static_cast<std::int64_t>(p.left.ticks64) * 125 / 6);
  }
  EXPECT_EQ(h.counters.unpaired.load(), 0u);
  EXPECT_EQ(h.channel.pool.available(), 16u - 6u);  // nothing leaked by the pairer
}

TEST(Pairer, RightBeforeLeftPairsWithANegativeOffset) {
  Harness h;
  h.run(test::alternating(4, 0, 500'000, 1'089'600, -300'000));
  ASSERT_EQ(h.channel.pairs.size(), 4u);
  EXPECT_EQ(h.channel.pairs[0]->offset_ns(), -6'250'000);
}

TEST(Pairer, ToleranceDecides) {
  const auto recs = test::alternating(5, 0, 1000, 1'089'600, 528'000);  // 11 ms apart
  PairerSettings tight;
  tight.tolerance_ns = 10'000'000;
  Harness a(tight);
  a.run(recs);
  EXPECT_EQ(a.channel.pairs.size(), 0u);
  EXPECT_EQ(a.counters.unpaired.load(), 10u);
  PairerSettings loose;
  loose.tolerance_ns = 11'200'000;
  Harness b(loose);
  b.run(recs);
  EXPECT_EQ(b.channel.pairs.size(), 5u);
  EXPECT_EQ(b.counters.unpaired.load(), 0u);
  EXPECT_EQ(b.channel.pool.available(), 16u - 5u);
}

TEST(Pairer, NonAlternatingOrderStillPairsByTime) {
  // L0 R0 R1 L1 L2 R2 L3 L4 R3 R4 (each Rk 2 ms after Lk)
  const std::uint32_t P = 1'089'600, d = 96'000;
  std::vector<RecordSpec> recs = {{0, Sensor::left, 0},          {1, Sensor::right, d},
                                  {2, Sensor::right, P + d},     {3, Sensor::left, P},
                                  {4, Sensor::left, 2 * P},      {5, Sensor::right, 2 * P + d},
                                  {6, Sensor::left, 3 * P},      {7, Sensor::left, 4 * P},
                                  {8, Sensor::right, 3 * P + d}, {9, Sensor::right, 4 * P + d}};
  Harness h;
  h.run(recs);
  ASSERT_EQ(h.channel.pairs.size(), 5u);
  std::vector<std::uint32_t> lefts;
  for (const auto& p : h.channel.pairs) {
    EXPECT_EQ(p->right.ticks - p->left.ticks, d);
    lefts.push_back(p->left.ticks);
  }
  std::sort(lefts.begin(), lefts.end());
  EXPECT_EQ(lefts, (std::vector<std::uint32_t>{0, P, 2 * P, 3 * P, 4 * P}));
  EXPECT_EQ(h.counters.unpaired.load(), 0u);
}

TEST(Pairer, TimestampWrapIsExtendedTo64Bits) {
  const std::uint32_t P = 1'089'600;
  const auto recs = test::alternating(6, 0, 0xFFFFFFFFu - 3 * P, P, 100'000);
  Harness h;
  h.run(recs);
  ASSERT_EQ(h.channel.pairs.size(), 6u);
  for (std::size_t k = 1; k < 6; ++k) {
    const StereoPair& a = *h.channel.pairs[k - 1];
    const StereoPair& b = *h.channel.pairs[k];
    EXPECT_EQ(b.left.ticks64 - a.left.ticks64, P) << k;
    EXPECT_EQ(b.offset_ns(), 100'000 * 125 / 6);
  }
  EXPECT_GT(h.channel.pairs[5]->left.ticks64, 0xFFFFFFFFull);
  EXPECT_LT(h.channel.pairs[5]->left.ticks, 0xFFFFFFFFu - 3 * P);  // the raw value did wrap
}

TEST(Pairer, MissingPartnersAreCountedAndBuffersReturn) {
  auto recs = test::alternating(6);
  recs.erase(recs.begin() + 5);  // right of pair 2
  recs.erase(recs.begin() + 6);  // left of pair 3 (was index 7)
  Harness h;
  h.run(recs);
  EXPECT_EQ(h.channel.pairs.size(), 4u);
  EXPECT_EQ(h.counters.unpaired.load(), 2u);
  EXPECT_EQ(h.pairer.waiting(), 0u);
  h.channel.pairs.clear();
  EXPECT_EQ(h.channel.pool.available(), 16u);
}

TEST(Pairer, OneSensorDeadKeepsAtMostMaxPending) {
  std::vector<RecordSpec> recs;
  for (int k = 0; k < 40; ++k) recs.push_back({static_cast<std::uint8_t>(k), Sensor::left, k * 1'089'600u});
  PairerSettings s;
  s.max_pending = 3;
  Harness h(s);
  const auto bytes = test::build(recs, kSize);
  h.parser.feed(bytes, 0);
  EXPECT_LE(h.pairer.waiting(), 3u);
  EXPECT_GE(h.channel.pool.available(), 16u - 4u);
  h.parser.finish(0);
  h.pairer.flush();
  EXPECT_EQ(h.counters.unpaired.load(), 40u);
}

TEST(Pairer, LoopedStreamContinuesTheTimeline) {
  const auto recs = test::alternating(3);
  Harness h;
  const auto bytes = test::build(recs, kSize);
  h.parser.feed(bytes, 0);
  h.parser.finish(0);
  h.pairer.flush(true);
  h.parser.feed(bytes, 0);
  h.parser.finish(0);
  ASSERT_EQ(h.channel.pairs.size(), 6u);
  EXPECT_GT(h.channel.pairs[3]->left.ticks64, h.channel.pairs[2]->left.ticks64);
  EXPECT_EQ(h.channel.pairs[4]->left.ticks64 - h.channel.pairs[3]->left.ticks64, 1'089'600u);
}

}  // namespace
}  // namespace naneye::driver
