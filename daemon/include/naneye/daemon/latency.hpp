#pragma once
// Latency statistics written by the worker and read by HTTP threads, lock-free and allocation-free
// on the writing side: a Prometheus-style cumulative histogram plus a ring of the most recent
// samples for percentiles.
#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace naneye::daemon {

class LatencyRecorder {
 public:
  // Upper bounds of the histogram buckets, seconds (the "le" labels); +Inf is implicit.
  static constexpr std::array<double, 12> kBounds{0.0001, 0.00025, 0.0005, 0.001, 0.002, 0.003,
                                                  0.005,  0.01,    0.025,  0.05,  0.1,   1.0};
  static constexpr std::size_t kRecent = 2048;

  void record(std::int64_t ns);  // worker only

  struct Snapshot {
    std::array<std::uint64_t, kBounds.size() + 1> buckets{};  // non-cumulative; last is +Inf
    std::uint64_t count = 0;
    double sum_s = 0;
    double p50_ms = 0, p99_ms = 0, max_ms = 0;  // over the most recent samples (up to kRecent)
  };
  Snapshot snapshot() const;  // any thread; allocates (HTTP side only)

 private:
  std::array<std::atomic<std::uint64_t>, kBounds.size() + 1> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::uint64_t> sum_ns_{0};
  std::array<std::atomic<std::int64_t>, kRecent> recent_{};
};

// Percentile (0..1) of `v` (sorted in place), nearest rank. 0 for an empty vector.
double percentile(std::vector<double>& v, double q);

}  // namespace naneye::daemon
