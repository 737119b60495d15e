#pragma once
// The benchmarks' clock: CPU time of the calling thread (user and system), seconds. Per-pair times
// are this thread's work alone, whatever else the machine runs (it shares its cores here).
#include <time.h>

namespace naneye::bench {

inline double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace naneye::bench
