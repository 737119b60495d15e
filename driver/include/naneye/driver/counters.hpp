#pragma once
// AtomicCounters: the live side of SourceCounters. The capture thread (parser, pairer, backend)
// increments with relaxed atomics; any thread takes a consistent-enough snapshot() at any time.
// Counters are monotonic, so relaxed ordering is all a reader needs.
#include <atomic>
#include <cstdint>

#include "naneye/driver/frame_source.hpp"

namespace naneye::driver {

struct AtomicCounters {
  std::atomic<std::uint64_t> bytes{0}, records{0}, sync_losses{0}, seq_gaps{0}, cut_records{0},
      corrupt_records{0}, reference_failures{0}, reference_unchecked{0}, unpaired{0}, pairs{0},
      pairs_dropped{0}, reconnects{0}, transfer_errors{0}, stalls{0};

  static void add(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) {
    c.fetch_add(n, std::memory_order_relaxed);
  }

  SourceCounters snapshot() const {
    const auto r = [](const std::atomic<std::uint64_t>& c) { return c.load(std::memory_order_relaxed); };
    SourceCounters s;
    s.bytes = r(bytes);
    s.records = r(records);
    s.sync_losses = r(sync_losses);
    s.seq_gaps = r(seq_gaps);
    s.cut_records = r(cut_records);
    s.corrupt_records = r(corrupt_records);
    s.reference_failures = r(reference_failures);
    s.reference_unchecked = r(reference_unchecked);
    s.unpaired = r(unpaired);
    s.pairs = r(pairs);
    s.pairs_dropped = r(pairs_dropped);
    s.reconnects = r(reconnects);
    s.transfer_errors = r(transfer_errors);
    s.stalls = r(stalls);
    return s;
  }
};

}  // namespace naneye::driver
