#pragma once
// Loggers: one per module, named after it ("driver", "sim", "daemon", "cli"), made in one way.
//
// A program's main() calls program_logger() once, first: its logger writes to stderr (stdout stays
// for machine-readable output) and becomes spdlog's default. Every module then asks module_logger()
// for its own, which shares the default logger's sinks and takes its level when it is first made.
// Both are thread-safe: racing first calls get the same logger. Neither ever returns null.
#include <spdlog/spdlog.h>

#include <memory>
#include <string_view>

namespace naneye::base {

// The logger registered under `name`, or a new one with the default logger's sinks, registered.
std::shared_ptr<spdlog::logger> module_logger(std::string_view name);

// The program's own logger: colour on stderr, registered under `name`, made the default logger.
std::shared_ptr<spdlog::logger> program_logger(std::string_view name);

}  // namespace naneye::base
