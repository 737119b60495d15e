// The hot path allocates nothing per frame: after construction, parsing, pairing and handing over
// any number of records makes no heap allocation (counted by tests/support/heap_count.cpp's operator new).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "../support/heap_count.hpp"
#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"
#include "naneye/driver/pairer.hpp"
#include "stream_builder.hpp"

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

  const long before = naneye::test::heap_allocations();
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
  const long allocations = naneye::test::heap_allocations() - before;

  EXPECT_EQ(allocations, 0);
  EXPECT_GT(popped, 50u);
  EXPECT_EQ(counters.sync_losses.load(), 1u);
  EXPECT_EQ(counters.corrupt_records.load(), 1u);
  EXPECT_EQ(counters.unpaired.load(), 2u);  // the partners of the two lost records
  EXPECT_EQ(popped + channel.ring.dropped(), (counters.records.load() - 2) / 2);
  EXPECT_EQ(channel.pool.available(), channel.pool.capacity());
}

}  // namespace
}  // namespace naneye::driver
