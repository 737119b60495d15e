#pragma once
// The loop every command that reads a source runs (recon, calibrate, replay, fixed-pattern): each
// pair of a started source handed to `f`, until the source has ended or `max_pairs` were handed.
#include <functional>

#include "naneye/driver/frame_source.hpp"

namespace naneye::tools {

// max_pairs < 0: every pair. Returns the pairs handed over. Polls next() every 200 ms, so a live
// source that has stalled still lets its end be seen.
long long for_each_pair(driver::FrameSource& source, long long max_pairs,
                        const std::function<void(driver::StereoPair&)>& f);

}  // namespace naneye::tools
