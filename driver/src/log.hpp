#pragma once
// The module's one logger, "driver" (created on first use from the default logger's sinks).
#include <spdlog/spdlog.h>

#include <memory>

namespace naneye::driver {

inline std::shared_ptr<spdlog::logger> log() {
  if (auto l = spdlog::get("driver")) return l;
  auto l = spdlog::default_logger()->clone("driver");
  try {
    spdlog::register_logger(l);
  } catch (const spdlog::spdlog_ex&) {
    return spdlog::get("driver");  // another thread registered it first
  }
  return l;
}

}  // namespace naneye::driver
