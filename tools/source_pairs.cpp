#include "source_pairs.hpp"

#include <chrono>

namespace naneye::tools {

long long for_each_pair(driver::FrameSource& source, long long max_pairs,
                        const std::function<void(driver::StereoPair&)>& f) {
  long long n = 0;
  while (max_pairs < 0 || n < max_pairs) {
    driver::PairPtr pair = source.next(std::chrono::milliseconds(200));
    if (!pair) {
      if (driver::has_ended(source.state())) break;
      continue;
    }
    f(*pair);
    ++n;
  }
  return n;
}

}  // namespace naneye::tools
