#pragma once
// Command-line inputs shared by several subcommands (recon, calibrate).
#include <string>

namespace naneye::tools {

// "ROWSxCOLS" inner corners, at most recon::kMaxCorners; std::invalid_argument naming the flag.
void parse_pattern(const std::string& text, int& rows, int& cols);

// A plain path, or a file:// URI without a speed, becomes a replay at max speed: every pair handed
// over (lossless), without taking the capture's duration. Other URIs are kept as given.
std::string lossless_input_uri(const std::string& input);

}  // namespace naneye::tools
