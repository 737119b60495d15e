// The hot path allocates nothing per frame: after construction, parsing, pairing and handing over
// any number of records makes no heap allocation (counted by replacing operator new in this binary).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"
#include "naneye/driver/pairer.hpp"
#include "stream_builder.hpp"

namespace {
std::atomic<bool> g_counting{false};
std::atomic<std::size_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
// GCC cannot see that operator new above is malloc-based.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace naneye::driver {
namespace {

// Pool + ring as a live source wires them (drop the oldest when the pool is dry).
struct RingChannel : PairChannel {
  PairPool pool{8};
  PairRing ring{3, PairRing::Policy::drop_oldest, pool.deleter()};
  PairPtr acquire() override {
    PairPtr p = pool.try_acquire();
    while (!p && ring.drop_oldest()) p = pool.try_acquire();
    return p;
  }
  void deliver(PairPtr p) override { ring.push(std::move(p)); }
};

TEST(NoAllocation, ParsingPairingAndHandOverAllocateNothingPerFrame) {
  const auto recs = test::alternating(40, 17);
  const auto bytes = test::build(recs);
  auto damaged = bytes;
  damaged[5 * kRecordSize + 3] = 0;        // a broken header: sync loss and reacquisition
  damaged[9 * kRecordSize + 4001] = 0x80;  // an out-of-range pixel
  RingChannel channel;
  AtomicCounters counters;
  Pairer pairer(PairerSettings{}, channel, counters);
  StreamParser parser(ParserSettings{}, pairer, counters);
  std::uint64_t popped = 0;

  g_allocations = 0;
  g_counting = true;
  for (int pass = 0; pass < 3; ++pass) {
    const auto& stream = pass == 1 ? damaged : bytes;
    for (std::size_t i = 0; i < stream.size(); i += 16384) {
      parser.feed(std::span(stream).subspan(i, std::min<std::size_t>(16384, stream.size() - i)), 0);
      if (i % (3 * 16384) == 0)
        while (PairPtr p = channel.ring.try_pop()) ++popped;
    }
    parser.finish(0);
    pairer.flush(true);
  }
  while (PairPtr p = channel.ring.try_pop()) ++popped;
  g_counting = false;

  EXPECT_EQ(g_allocations.load(), 0u);
  EXPECT_GT(popped, 50u);
  EXPECT_EQ(counters.sync_losses.load(), 1u);
  EXPECT_EQ(counters.corrupt_records.load(), 1u);
  EXPECT_EQ(counters.unpaired.load(), 2u);  // the partners of the two lost records
  EXPECT_EQ(popped + channel.ring.dropped(), (counters.records.load() - 2) / 2);
  EXPECT_EQ(channel.pool.available(), channel.pool.capacity());
}

}  // namespace
}  // namespace naneye::driver
