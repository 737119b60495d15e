#pragma once
// The module's one logger, "daemon" (base/log.hpp). naneyed's main() makes it the program logger
// (stderr, the default); elsewhere (tests) it shares the default logger's sinks.
#include "naneye/base/log.hpp"

namespace naneye::daemon {

inline std::shared_ptr<spdlog::logger> log() {
  return base::module_logger("daemon");
}

}  // namespace naneye::daemon
