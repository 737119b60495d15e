// The frame pool and the lock-free hand-over ring, including both policies under two threads.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"

namespace naneye::driver {
namespace {

using namespace std::chrono_literals;

TEST(PairPool, HandsOutEachBufferOnceAndTakesItBack) {
  PairPool pool(3);
  PairPtr a = pool.try_acquire(), b = pool.try_acquire(), c = pool.try_acquire();
  ASSERT_TRUE(a && b && c);
  EXPECT_NE(a.get(), b.get());
  EXPECT_NE(b.get(), c.get());
  EXPECT_TRUE(pool.owns(a.get()));
  EXPECT_FALSE(pool.try_acquire());
  EXPECT_EQ(pool.available(), 0u);
  StereoPair* raw = b.get();
  b.reset();
  EXPECT_EQ(pool.available(), 1u);
  PairPtr d = pool.try_acquire();
  EXPECT_EQ(d.get(), raw);
}

TEST(PairPool, AcquireWaitsForARelease) {
  PairPool pool(1);
  PairPtr held = pool.try_acquire();
  std::thread releaser([&] {
    std::this_thread::sleep_for(30ms);
    held.reset();
  });
  PairPtr p = pool.acquire_until(std::chrono::steady_clock::now() + 5s);
  releaser.join();
  EXPECT_TRUE(p);
  std::atomic<bool> stop{true};
  EXPECT_FALSE(pool.acquire_until(std::chrono::steady_clock::now() + 5s, &stop));
}

TEST(PairRing, DropOldestKeepsTheNewestAndCounts) {
  PairPool pool(8);
  PairRing ring(3, PairRing::Policy::drop_oldest, pool.deleter());
  for (std::uint64_t i = 0; i < 5; ++i) {
    PairPtr p = pool.try_acquire();
    p->index = i;
    ASSERT_TRUE(ring.push(std::move(p)));
  }
  EXPECT_EQ(ring.dropped(), 2u);
  EXPECT_EQ(pool.available(), 5u);  // dropped pairs went back to the pool
  for (std::uint64_t want = 2; want < 5; ++want) {
    PairPtr p = ring.try_pop();
    ASSERT_TRUE(p);
    EXPECT_EQ(p->index, want);
  }
  EXPECT_FALSE(ring.try_pop());
}

// Producer faster than consumer: every pair is either received (in order) or counted as dropped,
// and every buffer returns to the pool. Run it under -DNANEYE_TSAN=ON to check the orderings.
TEST(PairRing, DropOldestUnderContention) {
  constexpr std::uint64_t kPairs = 20000;
  PairPool pool(6);
  PairRing ring(4, PairRing::Policy::drop_oldest, pool.deleter());
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kPairs; ++i) {
      PairPtr p = pool.try_acquire();
      while (!p) {  // the consumer holds one, the ring the rest: take the oldest back
        ring.drop_oldest();
        p = pool.try_acquire();
      }
      p->index = i;
      p->left.ticks = static_cast<std::uint32_t>(i);
      ring.push(std::move(p));
    }
    ring.close();
  });
  std::uint64_t received = 0, last = 0;
  bool first = true, ordered = true, intact = true;
  for (;;) {
    PairPtr p = ring.pop_until(std::chrono::steady_clock::now() + 2s);
    if (!p) break;
    if (!first && p->index <= last) ordered = false;
    if (p->left.ticks != static_cast<std::uint32_t>(p->index)) intact = false;
    first = false;
    last = p->index;
    ++received;
    if (received % 64 == 0) std::this_thread::sleep_for(50us);
  }
  producer.join();
  EXPECT_TRUE(ordered);
  EXPECT_TRUE(intact);
  EXPECT_EQ(received + ring.dropped(), kPairs);
  EXPECT_GT(ring.dropped(), 0u);
  EXPECT_GT(received, 0u);
  EXPECT_EQ(pool.available(), pool.capacity());
}

TEST(PairRing, BlockingIsLosslessUnderContention) {
  constexpr std::uint64_t kPairs = 5000;
  PairPool pool(6);
  PairRing ring(2, PairRing::Policy::block, pool.deleter());
  std::atomic<bool> stop{false};
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kPairs; ++i) {
      PairPtr p = pool.acquire_until(std::chrono::steady_clock::time_point::max(), &stop);
      p->index = i;
      ASSERT_TRUE(ring.push(std::move(p), &stop));
    }
    ring.close();
  });
  std::uint64_t expected = 0;
  bool ordered = true;
  while (PairPtr p = ring.pop_until(std::chrono::steady_clock::now() + 5s)) {
    if (p->index != expected) ordered = false;
    ++expected;
    if (expected % 100 == 0) std::this_thread::sleep_for(200us);
  }
  producer.join();
  EXPECT_TRUE(ordered);
  EXPECT_EQ(expected, kPairs);
  EXPECT_EQ(ring.dropped(), 0u);
  EXPECT_EQ(pool.available(), pool.capacity());
}

TEST(PairRing, BlockedProducerLeavesOnStop) {
  PairPool pool(4);
  PairRing ring(1, PairRing::Policy::block, pool.deleter());
  std::atomic<bool> stop{false};
  ASSERT_TRUE(ring.push(pool.try_acquire(), &stop));
  std::atomic<bool> result{true};
  std::thread producer([&] { result = ring.push(pool.try_acquire(), &stop); });
  std::this_thread::sleep_for(30ms);
  stop = true;
  ring.wake_producer();
  producer.join();
  EXPECT_FALSE(result.load());
  EXPECT_EQ(ring.size(), 1u);
  EXPECT_EQ(pool.available(), 3u);  // the refused pair went back
}

TEST(PairRing, PopTimesOutWhenEmptyAndEndsWhenClosed) {
  PairPool pool(2);
  PairRing ring(2, PairRing::Policy::drop_oldest, pool.deleter());
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(ring.pop_until(t0 + 20ms));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 20ms);
  ring.push(pool.try_acquire());
  ring.close();
  EXPECT_TRUE(ring.pop_until(std::chrono::steady_clock::now() + 1s));
  EXPECT_FALSE(ring.pop_until(std::chrono::steady_clock::now() + 10s));  // closed and empty: at once
  EXPECT_FALSE(ring.push(pool.try_acquire()));
}

}  // namespace
}  // namespace naneye::driver
