#pragma once
// The module's one logger, "sim" (base/log.hpp: shares the default logger's sinks).
#include "naneye/base/log.hpp"

namespace naneye::sim {

inline std::shared_ptr<spdlog::logger> log() {
  return base::module_logger("sim");
}

}  // namespace naneye::sim
