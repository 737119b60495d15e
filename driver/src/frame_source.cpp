#include "naneye/driver/frame_source.hpp"

namespace naneye::driver {

const char* to_string(SourceState s) {
  switch (s) {
    case SourceState::starting:
      return "starting";
    case SourceState::streaming:
      return "streaming";
    case SourceState::waiting_for_device:
      return "waiting_for_device";
    case SourceState::stalled:
      return "stalled";
    case SourceState::finished:
      return "finished";
    case SourceState::failed:
      return "failed";
    case SourceState::stopped:
      return "stopped";
  }
  return "unknown";
}

bool has_ended(SourceState s) {
  return s == SourceState::finished || s == SourceState::failed || s == SourceState::stopped;
}

}  // namespace naneye::driver
