#include "naneye/base/log.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <mutex>
#include <string>

namespace naneye::base {
namespace {

std::mutex& registry_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

std::shared_ptr<spdlog::logger> module_logger(std::string_view name) {
  const std::string key(name);
  if (auto l = spdlog::get(key)) return l;
  std::lock_guard lock(registry_mutex());
  if (auto l = spdlog::get(key)) return l;  // made by another thread while this one waited
  auto l = spdlog::default_logger()->clone(key);
  try {
    spdlog::register_logger(l);
  } catch (const spdlog::spdlog_ex&) {
    return spdlog::get(key);  // registered outside this function in the meantime
  }
  return l;
}

std::shared_ptr<spdlog::logger> program_logger(std::string_view name) {
  const std::string key(name);
  std::shared_ptr<spdlog::logger> l;
  {
    std::lock_guard lock(registry_mutex());
    l = spdlog::get(key);
    if (!l) l = spdlog::stderr_color_mt(key);
  }
  spdlog::set_default_logger(l);
  return l;
}

}  // namespace naneye::base
