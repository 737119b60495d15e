#pragma once
// The module's one logger, "driver" (base/log.hpp: shares the default logger's sinks).
#include "naneye/base/log.hpp"

namespace naneye::driver {

inline std::shared_ptr<spdlog::logger> log() {
  return base::module_logger("driver");
}

}  // namespace naneye::driver
