#include "cli_inputs.hpp"

#include <cstdio>
#include <stdexcept>

#include "naneye/recon/pair/result.hpp"

namespace naneye::tools {

recon::BoardGeometry parse_board(const std::string& pattern, double square_mm) {
  recon::BoardGeometry board;  // the default square until the grid is known good: its check is the grid's
  char x = 0;
  if (std::sscanf(pattern.c_str(), "%d%c%d", &board.rows, &x, &board.cols) != 3 || (x != 'x' && x != 'X') ||
      !board.check().empty() || board.count() > recon::kMaxCorners)
    throw std::invalid_argument("--pattern must be ROWSxCOLS inner corners (e.g. " + pattern_text({}) +
                                "), at most " + std::to_string(recon::kMaxCorners) + " corners; got '" +
                                pattern + "'");
  board.square_mm = square_mm;
  if (const auto why = board.check(); !why.empty()) throw std::invalid_argument("--square-mm: " + why);
  return board;
}

std::string pattern_text(const recon::BoardGeometry& board) {
  return std::to_string(board.rows) + "x" + std::to_string(board.cols);
}

std::string lossless_input_uri(const std::string& input) {
  std::string uri = input.find("://") == std::string::npos ? "file://" + input : input;
  if (uri.rfind("file://", 0) == 0 && uri.find("speed=") == std::string::npos)
    uri += (uri.find('?') == std::string::npos ? "?" : "&") + std::string("speed=max");
  return uri;
}

}  // namespace naneye::tools
