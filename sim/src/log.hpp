#pragma once
// The module's logger ("sim"), created on first use next to whatever the program registered.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <memory>

namespace naneye::sim {

inline std::shared_ptr<spdlog::logger> log() {
  if (auto l = spdlog::get("sim")) return l;
  try {
    return spdlog::stderr_color_mt("sim");
  } catch (const spdlog::spdlog_ex&) {  // another thread registered it first
    return spdlog::get("sim");
  }
}

}  // namespace naneye::sim
