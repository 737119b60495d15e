#pragma once
// The viewer's files (daemon/web/), embedded at build time by cmake/embed_files.cmake.
#include <span>
#include <string_view>

namespace naneye::daemon::web {

struct Asset {
  std::string_view name;  // relative to daemon/web/, e.g. "viewer.js"
  std::string_view data;
};

std::span<const Asset> assets();

}  // namespace naneye::daemon::web
