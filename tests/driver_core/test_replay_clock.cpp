// ReplayClock: a replay keeps the recorded spacing, and a replay held by the machine goes on from
// its late record instead of releasing the records of the gap at once (replay_clock.hpp).
#include "naneye/driver/replay_clock.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace naneye::driver {
namespace replay_clock_test {

using namespace std::chrono_literals;
using Tp = ReplayClock::time_point;

constexpr std::int64_t kPeriodNs = 16'129'032;  // 62 fps
const Tp t0 = Tp{} + 1000s;

TEST(ReplayClock, RecordsAreDueAtTheirRecordedSpacingFromThePassStart) {
  ReplayClock c;
  EXPECT_EQ(c.due(5'000'000'000, t0), t0);  // the first record at once, whatever its epoch
  Tp now = t0;
  for (int k = 1; k < 10; ++k) {
    const Tp due = c.due(5'000'000'000 + k * kPeriodNs, now);
    EXPECT_EQ(due - t0, std::chrono::nanoseconds(k * kPeriodNs));
    now = due + 3ms;  // woken late, within a loaded machine's jitter: caught up, not moved
  }
  EXPECT_EQ(c.resyncs(), 0u);
}

TEST(ReplayClock, AHeldReplayGoesOnFromItsLateRecordAtTheRecordedSpacing) {
  ReplayClock c;
  c.due(0, t0);
  EXPECT_EQ(c.due(kPeriodNs, t0 + 16ms), t0 + std::chrono::nanoseconds(kPeriodNs));
  // Held 400 ms before asking for record 2: it is due now, not 383 ms ago with 23 others behind it.
  const Tp back = t0 + 2 * std::chrono::nanoseconds(kPeriodNs) + 400ms;
  EXPECT_EQ(c.due(2 * kPeriodNs, back), back);
  EXPECT_EQ(c.resyncs(), 1u);
  for (int k = 3; k < 8; ++k)
    EXPECT_EQ(c.due(k * kPeriodNs, back), back + (k - 2) * std::chrono::nanoseconds(kPeriodNs));
  // Late by exactly the bound is jitter; one nanosecond more is a hold.
  const Tp at8 = back + 6 * std::chrono::nanoseconds(kPeriodNs);
  EXPECT_EQ(c.due(8 * kPeriodNs, at8 + ReplayClock::kHeldAfter), at8);
  const Tp at9 = at8 + std::chrono::nanoseconds(kPeriodNs);
  EXPECT_EQ(c.due(9 * kPeriodNs, at9 + ReplayClock::kHeldAfter + 1ns), at9 + ReplayClock::kHeldAfter + 1ns);
  EXPECT_EQ(c.resyncs(), 2u);
}

TEST(ReplayClock, AFactorDividesRecordedTimeAndARestartBeginsANewPass) {
  ReplayClock c(4.0);
  c.due(0, t0);
  EXPECT_EQ(c.due(400'000'000, t0), t0 + 100ms);
  c.restart();
  EXPECT_EQ(c.due(400'000'000, t0 + 5s), t0 + 5s);  // loop=1: the next pass starts at once
  EXPECT_EQ(c.due(800'000'000, t0 + 5s), t0 + 5s + 100ms);
  EXPECT_THROW(ReplayClock(0.0), std::invalid_argument);
  EXPECT_THROW(ReplayClock(-1.0), std::invalid_argument);
}

}  // namespace replay_clock_test
}  // namespace naneye::driver
