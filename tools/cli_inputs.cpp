#include "cli_inputs.hpp"

#include <cstdio>
#include <stdexcept>

#include "naneye/recon/pair/result.hpp"

namespace naneye::tools {

void parse_pattern(const std::string& text, int& rows, int& cols) {
  char x = 0;
  if (std::sscanf(text.c_str(), "%d%c%d", &rows, &x, &cols) != 3 || (x != 'x' && x != 'X') || rows < 2 ||
      cols < 2 || rows * cols > recon::kMaxCorners)
    throw std::invalid_argument("--pattern must be ROWSxCOLS inner corners (e.g. 6x8), at most " +
                                std::to_string(recon::kMaxCorners) + " corners; got '" + text + "'");
}

std::string lossless_input_uri(const std::string& input) {
  std::string uri = input.find("://") == std::string::npos ? "file://" + input : input;
  if (uri.rfind("file://", 0) == 0 && uri.find("speed=") == std::string::npos)
    uri += (uri.find('?') == std::string::npos ? "?" : "&") + std::string("speed=max");
  return uri;
}

}  // namespace naneye::tools
