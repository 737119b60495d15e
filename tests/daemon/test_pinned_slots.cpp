// The lock-free publication between the worker and HTTP readers. Run under ThreadSanitizer too
// (test_daemon_tsan, NANEYE_TSAN=ON): every access must be ordered by the slots' atomics.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <thread>
#include <vector>

#include "naneye/daemon/pinned_slots.hpp"

using naneye::daemon::PinnedSlots;

namespace {

// A value that is only consistent when written whole: every word equals the sequence number.
struct Block {
  std::array<std::uint64_t, 512> words{};
};

}  // namespace

TEST(PinnedSlots, NothingBeforeTheFirstPublication) {
  PinnedSlots<Block> slots(4);
  EXPECT_FALSE(slots.read_latest([](const Block&, std::uint64_t) {}));
  EXPECT_FALSE(slots.latest_seq().has_value());
}

TEST(PinnedSlots, LatestAndHistoryAreWhatWasPublished) {
  PinnedSlots<Block> slots(4);
  for (std::uint64_t s = 1; s <= 6; ++s) {
    Block* b = slots.begin_write();
    ASSERT_NE(b, nullptr);
    b->words.fill(s);
    slots.publish(s);
  }
  std::uint64_t seen = 0;
  ASSERT_TRUE(slots.read_latest([&](const Block& b, std::uint64_t seq) {
    EXPECT_EQ(b.words[0], seq);
    seen = seq;
  }));
  EXPECT_EQ(seen, 6u);
  // Four slots hold the last four publications; older ones are gone.
  for (std::uint64_t s = 3; s <= 6; ++s) {
    EXPECT_TRUE(slots.read_seq(s, [&](const Block& b) { EXPECT_EQ(b.words[100], s); })) << s;
  }
  EXPECT_FALSE(slots.read_seq(2, [](const Block&) {}));
}

TEST(PinnedSlots, WriterSkipsPinnedSlotsInsteadOfWaiting) {
  PinnedSlots<Block> slots(2);
  Block* b = slots.begin_write();
  b->words.fill(1);
  slots.publish(1);
  // While a reader holds the only other candidate (the published one), the writer gets the free one;
  // while the reader holds slot 1 and slot 0 is the published one, the writer gets nothing.
  bool inner_ran = false;
  slots.read_latest([&](const Block&, std::uint64_t) {
    Block* w = slots.begin_write();
    ASSERT_NE(w, nullptr);
    w->words.fill(2);
    slots.publish(2);
    slots.read_latest([&](const Block& latest, std::uint64_t seq) {
      EXPECT_EQ(seq, 2u);
      EXPECT_EQ(latest.words[0], 2u);
      EXPECT_EQ(slots.begin_write(), nullptr);  // both slots pinned: skip, never wait
      inner_ran = true;
    });
  });
  EXPECT_TRUE(inner_ran);
  EXPECT_NE(slots.begin_write(), nullptr);
  slots.abandon();
}

TEST(PinnedSlots, ReadersNeverSeeATornValueUnderConcurrentPublication) {
  PinnedSlots<Block> slots(6);
  constexpr std::uint64_t kPublications = 100000;
  std::atomic<bool> done{false};
  std::atomic<int> started{0};
  std::atomic<std::uint64_t> skipped{0};
  std::thread writer([&] {
    while (started.load() < 2) std::this_thread::yield();
    for (std::uint64_t s = 1; s <= kPublications; ++s) {
      Block* b = slots.begin_write();
      if (!b) {
        skipped.fetch_add(1);
        continue;
      }
      b->words.fill(s);
      slots.publish(s);
    }
    done.store(true);
  });
  auto reader = [&](std::uint64_t& reads, std::uint64_t& torn, std::uint64_t& backwards) {
    std::uint64_t last = 0;
    started.fetch_add(1);
    while (!done.load()) {
      slots.read_latest([&](const Block& b, std::uint64_t seq) {
        ++reads;
        for (auto w : b.words) torn += w != seq;
        backwards += seq < last;
        last = seq;
      });
      if (auto s = slots.latest_seq(); s && *s > 3) {
        slots.read_seq(*s - 3, [&](const Block& b) { torn += b.words[511] != *s - 3; });
      }
    }
  };
  std::uint64_t r1 = 0, t1 = 0, b1 = 0, r2 = 0, t2 = 0, b2 = 0;
  std::thread a([&] { reader(r1, t1, b1); });
  std::thread c([&] { reader(r2, t2, b2); });
  writer.join();
  a.join();
  c.join();
  EXPECT_EQ(t1 + t2, 0u) << "a reader saw a slot being written";
  EXPECT_EQ(b1 + b2, 0u) << "the latest went backwards";
  EXPECT_GT(r1 + r2, 0u);
  std::uint64_t last = 0;
  ASSERT_TRUE(slots.read_latest([&](const Block&, std::uint64_t seq) { last = seq; }));
  EXPECT_EQ(last + skipped.load() >= kPublications, true);
  EXPECT_LE(skipped.load(), kPublications / 100) << "two readers should rarely pin every other slot";
}
