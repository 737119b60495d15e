// Backoff (base/backoff.hpp): the delays, their cap and reset, the counters, and "say why once".
#include "naneye/base/backoff.hpp"

#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>

#include <string>
#include <vector>

using namespace naneye::base;
using std::chrono::milliseconds;

namespace {

struct Logged {
  spdlog::level::level_enum level;
  std::string text;
};

// A logger that keeps what it was given, at every level.
struct Recorder {
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink =
      std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(64);
  std::shared_ptr<spdlog::logger> log = std::make_shared<spdlog::logger>("backoff_test", sink);
  Recorder() { log->set_level(spdlog::level::trace); }
  std::vector<Logged> lines() {
    std::vector<Logged> out;
    for (const auto& m : sink->last_raw())
      out.push_back({m.level, std::string(m.payload.data(), m.payload.size())});
    return out;
  }
  int count(spdlog::level::level_enum level) {
    int n = 0;
    for (const auto& l : lines()) n += l.level == level;
    return n;
  }
};

}  // namespace

TEST(Backoff, DelaysGrowByTheFactorUpToTheCap) {
  Recorder r;
  Backoff b({.initial_ms = 100, .factor = 2.0, .max_ms = 500}, r.log, "test");
  EXPECT_EQ(b.next_delay(), milliseconds(100));
  EXPECT_EQ(b.next_delay(), milliseconds(200));
  EXPECT_EQ(b.next_delay(), milliseconds(400));
  EXPECT_EQ(b.next_delay(), milliseconds(500));
  EXPECT_EQ(b.next_delay(), milliseconds(500));
  b.reset();
  EXPECT_EQ(b.next_delay(), milliseconds(100));
}

TEST(Backoff, FailedAndLostReturnTheNextDelay) {
  Recorder r;
  Backoff b({.initial_ms = 20, .factor = 3.0, .max_ms = 1000}, r.log, "test");
  EXPECT_EQ(b.failed("absent"), milliseconds(20));
  EXPECT_EQ(b.failed("absent"), milliseconds(60));
  b.succeeded();
  EXPECT_EQ(b.failed("absent"), milliseconds(180));  // succeeded() leaves the delay: reset() is the caller's
  b.reset();
  EXPECT_EQ(b.lost("gone"), milliseconds(20));
}

TEST(Backoff, CountsAttemptsFailuresSuccessesRecoveriesAndLosses) {
  Recorder r;
  Backoff b({}, r.log, "test");
  b.failed("absent");
  b.succeeded();  // the first success: not a recovery
  b.lost("gone");
  b.failed("absent");
  b.failed("absent");
  b.succeeded();  // a reconnection
  const auto c = b.counters();
  EXPECT_EQ(c.attempts, 5u);
  EXPECT_EQ(c.failures, 3u);
  EXPECT_EQ(c.successes, 2u);
  EXPECT_EQ(c.recoveries, 1u);
  EXPECT_EQ(c.losses, 1u);
}

TEST(Backoff, TheSameReasonIsToldOnceAtWarn) {
  Recorder r;
  Backoff b({}, r.log, "usb");
  for (int i = 0; i < 10; ++i) b.failed("no board with id 10f8:c487");
  EXPECT_EQ(r.count(spdlog::level::warn), 1);
  EXPECT_EQ(r.count(spdlog::level::debug), 9);
  const auto first = r.lines().front();
  EXPECT_NE(first.text.find("usb: no board with id 10f8:c487"), std::string::npos) << first.text;
  EXPECT_NE(first.text.find("retrying in 100 ms"), std::string::npos) << first.text;
}

TEST(Backoff, AChangeOfReasonIsToldAgain) {
  Recorder r;
  Backoff b({}, r.log, "usb");
  b.failed("absent");
  b.failed("absent");
  b.failed("cannot claim interface 0");
  b.failed("cannot claim interface 0");
  b.failed("absent");
  EXPECT_EQ(r.count(spdlog::level::warn), 3);
  EXPECT_EQ(r.count(spdlog::level::debug), 2);
}

TEST(Backoff, RecoveryIsToldOnceWithTheAttemptsItTook) {
  Recorder r;
  Backoff b({}, r.log, "v4l2 /dev/video0");
  b.succeeded();  // no outage: nothing to tell
  EXPECT_TRUE(r.lines().empty());
  b.lost("device gone");
  b.failed("absent");
  b.failed("absent");
  b.succeeded();
  b.succeeded();  // already back: told once
  const auto lines = r.lines();
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].level, spdlog::level::warn);  // the loss, with its reason
  EXPECT_NE(lines[0].text.find("device gone"), std::string::npos) << lines[0].text;
  EXPECT_EQ(lines[1].level, spdlog::level::warn);  // why it cannot come back (a new reason)
  EXPECT_EQ(lines[2].level, spdlog::level::debug);
  EXPECT_EQ(lines[3].level, spdlog::level::info);
  EXPECT_NE(lines[3].text.find("back after"), std::string::npos) << lines[3].text;
  EXPECT_NE(lines[3].text.find("3 attempts"), std::string::npos) << lines[3].text;
  EXPECT_FALSE(b.in_outage());
}

TEST(Backoff, ANewOutageTellsItsReasonAgain) {
  Recorder r;
  Backoff b({}, r.log, "usb");
  b.failed("absent");
  b.succeeded();
  b.failed("absent");  // the same reason, but a new outage: told at warn
  EXPECT_EQ(r.count(spdlog::level::warn), 2);
}
