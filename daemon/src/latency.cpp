#include "naneye/daemon/latency.hpp"

#include <algorithm>
#include <cmath>

namespace naneye::daemon {

void LatencyRecorder::record(std::int64_t ns) {
  if (ns < 0) ns = 0;
  const double s = static_cast<double>(ns) * 1e-9;
  std::size_t b = 0;
  while (b < kBounds.size() && s > kBounds[b]) ++b;
  buckets_[b].fetch_add(1, std::memory_order_relaxed);
  sum_ns_.fetch_add(static_cast<std::uint64_t>(ns), std::memory_order_relaxed);
  const auto n = count_.load(std::memory_order_relaxed);
  recent_[n % kRecent].store(ns, std::memory_order_relaxed);
  count_.store(n + 1, std::memory_order_release);
}

LatencyRecorder::Snapshot LatencyRecorder::snapshot() const {
  Snapshot out;
  out.count = count_.load(std::memory_order_acquire);
  for (std::size_t b = 0; b < buckets_.size(); ++b)
    out.buckets[b] = buckets_[b].load(std::memory_order_relaxed);
  out.sum_s = static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-9;
  std::vector<double> ms;
  const auto held = std::min<std::uint64_t>(out.count, kRecent);
  ms.reserve(held);
  for (std::uint64_t i = 0; i < held; ++i)
    ms.push_back(static_cast<double>(recent_[i].load(std::memory_order_relaxed)) * 1e-6);
  out.p50_ms = percentile(ms, 0.50);
  out.p99_ms = percentile(ms, 0.99);
  out.max_ms = ms.empty() ? 0.0 : ms.back();
  return out;
}

double percentile(std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace naneye::daemon
