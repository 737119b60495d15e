#pragma once
// Both eyes' fixed patterns in one file (docs/sensor-calibration.md): OpenCV FileStorage, so
// `.yml.gz` compresses (4.6 MB of text to 1.1 MB for both eyes' maps) and `.yml` stays readable.
#include <filesystem>

#include "naneye/recon/camera/fixed_pattern.hpp"

namespace naneye::recon {

struct StereoFixedPattern {
  FixedPattern left, right;
};

// Throw std::runtime_error naming the file and what is wrong with it.
void save_fixed_pattern(const std::filesystem::path& file, const StereoFixedPattern& pattern);
StereoFixedPattern load_fixed_pattern(const std::filesystem::path& file);

}  // namespace naneye::recon
