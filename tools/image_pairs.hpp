#pragma once
// Stereo image pairs named on the command line (`naneye recon --left ... --right ...`).
#include <string>
#include <utility>
#include <vector>

#include "naneye/driver/image_file.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::tools {

// Each argument is a file or a glob pattern (quoted, so the shell leaves it: "left*.png"), whose
// matches are sorted by name; files are taken in the order given (a shell's own expansion is sorted
// already), and the two sides are paired in order. std::invalid_argument when a pattern matches
// nothing or the two sides differ in count.
std::vector<std::pair<std::string, std::string>> image_pairs(const std::vector<std::string>& left,
                                                             const std::vector<std::string>& right);

// A decoded image as the recon module sees it (no copy). A 250 x 250 image is taken for a NanEye
// frame saved whole (its padding column and reference rows are skipped, as for a capture); any other
// size is a foreign camera's picture, every pixel of it image.
recon::RawImageView image_view(const driver::Image10& image);

}  // namespace naneye::tools
