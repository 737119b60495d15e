// The per-pair step's second thread ([recon] threads = 2): a part runs once per start() on another
// thread, finish() returns only after it did and hands back what it threw, and the destructor waits
// for a part still running.
#include <gtest/gtest.h>

#include <chrono>
#include <stdexcept>
#include <thread>

#include "naneye/app/helper_thread.hpp"

using namespace naneye;

namespace helper_thread_test {

TEST(HelperThread, RunsThePartOncePerStartOnAnotherThreadAndFinishWaitsForIt) {
  int runs = 0;  // written by the helper only, read here after finish()
  std::thread::id where;
  app::HelperThread helper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));  // finish() must wait, not find it done
    where = std::this_thread::get_id();
    ++runs;
  });
  for (int k = 1; k <= 50; ++k) {
    helper.start();
    helper.finish();
    ASSERT_EQ(runs, k);
  }
  EXPECT_NE(where, std::this_thread::get_id());
  helper.finish();  // nothing started: returns at once
  EXPECT_EQ(runs, 50);
}

TEST(HelperThread, FinishRethrowsWhatThePartThrewAndTheHelperGoesOn) {
  int runs = 0;
  app::HelperThread helper([&] {
    if (++runs == 2) throw std::runtime_error("the second part failed");
  });
  helper.start();
  EXPECT_NO_THROW(helper.finish());
  helper.start();
  EXPECT_THROW(
      {
        try {
          helper.finish();
        } catch (const std::runtime_error& e) {
          EXPECT_STREQ(e.what(), "the second part failed");
          throw;
        }
      },
      std::runtime_error);
  helper.start();
  EXPECT_NO_THROW(helper.finish());  // the error was handed back once, not kept
  EXPECT_EQ(runs, 3);
}

TEST(HelperThread, TheDestructorWaitsForAPartStillRunning) {
  bool done = false;
  {
    app::HelperThread helper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
      done = true;
    });
    helper.start();
  }  // no finish(): the destructor's
  EXPECT_TRUE(done);
  // Destroyed at once after start(), often before the helper woke: the part still runs, once.
  for (int k = 0; k < 200; ++k) {
    int runs = 0;
    {
      app::HelperThread helper([&] { ++runs; });
      helper.start();
    }
    ASSERT_EQ(runs, 1) << "round " << k;
  }
  app::HelperThread never_started([] { FAIL() << "a part ran without a start()"; });
}

}  // namespace helper_thread_test
