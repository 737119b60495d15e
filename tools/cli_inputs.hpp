#pragma once
// Command-line inputs shared by several subcommands (recon, calibrate).
#include <string>

#include "naneye/recon/geometry/board.hpp"

namespace naneye::tools {

// --pattern "ROWSxCOLS" inner corners (at most recon::kMaxCorners) and --square-mm as a board;
// std::invalid_argument naming the flag.
recon::BoardGeometry parse_board(const std::string& pattern, double square_mm);
// The --pattern text of a board ("6x8"): the flags' defaults are recon::BoardGeometry's.
std::string pattern_text(const recon::BoardGeometry& board);

// A plain path, or a file:// URI without a speed, becomes a replay at max speed: every pair handed
// over (lossless), without taking the capture's duration. Other URIs are kept as given.
std::string lossless_input_uri(const std::string& input);

}  // namespace naneye::tools
