// log.hpp: one logger per module name, made once, sharing the default logger's sinks.
#include "naneye/base/log.hpp"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

using namespace naneye::base;

TEST(ModuleLogger, GivesTheSameLoggerForAName) {
  auto a = module_logger("base_test_a");
  ASSERT_TRUE(a);
  EXPECT_EQ(a, module_logger("base_test_a"));
  EXPECT_EQ(a, spdlog::get("base_test_a"));
  EXPECT_NE(a, module_logger("base_test_b"));
  EXPECT_EQ(a->sinks(), spdlog::default_logger()->sinks());
}

TEST(ModuleLogger, RacingFirstUsesGetOneLogger) {
  std::vector<std::shared_ptr<spdlog::logger>> got(8);
  std::vector<std::thread> threads;
  for (std::size_t i = 0; i < got.size(); ++i)
    threads.emplace_back([&got, i] { got[i] = module_logger("base_test_race"); });
  for (auto& t : threads) t.join();
  for (const auto& l : got) EXPECT_EQ(l, got.front());
}
