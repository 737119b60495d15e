#include "naneye/base/backoff.hpp"

#include <algorithm>

namespace naneye::base {

Backoff::Backoff(BackoffSettings settings, std::shared_ptr<spdlog::logger> log, std::string what)
    : s_(settings), log_(std::move(log)), what_(std::move(what)), delay_ms_(settings.initial_ms) {}

std::chrono::milliseconds Backoff::next_delay() {
  const auto now = std::chrono::milliseconds(static_cast<std::int64_t>(delay_ms_));
  delay_ms_ = std::min(delay_ms_ * s_.factor, static_cast<double>(s_.max_ms));
  return now;
}

void Backoff::reset() {
  delay_ms_ = s_.initial_ms;
}

void Backoff::start_outage() {
  if (in_outage_) return;
  in_outage_ = true;
  told_.clear();
  outage_attempts_ = 0;
  outage_start_ = std::chrono::steady_clock::now();
}

std::chrono::milliseconds Backoff::failed(std::string_view reason) {
  attempts_.fetch_add(1, std::memory_order_relaxed);
  failures_.fetch_add(1, std::memory_order_relaxed);
  start_outage();
  ++outage_attempts_;
  const auto delay = next_delay();
  const bool news = reason != told_;
  log_->log(news ? spdlog::level::warn : spdlog::level::debug,
            "{}: {}; retrying in {} ms (backoff up to {} ms)", what_, reason, delay.count(), s_.max_ms);
  if (news) told_ = reason;
  return delay;
}

void Backoff::succeeded() {
  attempts_.fetch_add(1, std::memory_order_relaxed);
  if (successes_.fetch_add(1, std::memory_order_relaxed) > 0)
    recoveries_.fetch_add(1, std::memory_order_relaxed);
  if (!in_outage_) return;
  in_outage_ = false;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - outage_start_).count();
  log_->info("{}: back after {:.1f} s and {} attempts", what_, s, outage_attempts_ + 1);
}

std::chrono::milliseconds Backoff::lost(std::string_view reason) {
  losses_.fetch_add(1, std::memory_order_relaxed);
  in_outage_ = false;  // a new outage, whatever the last one was
  start_outage();
  told_ = reason;
  log_->warn("{}: {}; reconnecting", what_, reason);
  return next_delay();
}

BackoffCounters Backoff::counters() const {
  return {attempts_.load(std::memory_order_relaxed), failures_.load(std::memory_order_relaxed),
          successes_.load(std::memory_order_relaxed), recoveries_.load(std::memory_order_relaxed),
          losses_.load(std::memory_order_relaxed)};
}

}  // namespace naneye::base
