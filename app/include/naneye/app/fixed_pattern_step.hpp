#pragma once
// The sensor's fixed pattern removed from both frames of a pair before anything reads them
// (recon/camera/fixed_pattern.hpp; docs/sensor-calibration.md): naneyed's [sensor] fixed_pattern and
// `naneye recon --fixed-pattern`. The corrected frames live in two buffers of its own, sized once:
// the pair itself (and what /v1/frame serves of it) stays as the camera gave it.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "naneye/recon/camera/fixed_pattern_io.hpp"

namespace naneye::app {

class FixedPatternStep {
 public:
  // Loads the file; std::runtime_error naming it when it cannot be used (unreadable, maps of
  // another size than frames_width x frames_height).
  FixedPatternStep(const std::filesystem::path& file, int frames_width, int frames_height);
  // The frame with the eye's pattern removed (0 left, 1 right): a view of this step's buffer, valid
  // until the next call for the same eye. Allocates nothing.
  recon::RawImageView correct(int eye, const recon::RawImageView& frame);
  // "fixed pattern removed (FILE: DSNU 3.9 DN, PRNU 2.1 %)", for the log and /v1/status.
  const std::string& description() const { return description_; }

 private:
  recon::StereoFixedPattern pattern_;
  std::vector<std::uint16_t> buffer_[2];
  std::string description_;
};

}  // namespace naneye::app
