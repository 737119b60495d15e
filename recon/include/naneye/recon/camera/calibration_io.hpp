#pragma once
// Calibration files: OpenCV FileStorage YAML with the keys of OpenCV's stereo_calib sample
// (M1 D1 M2 D2 R T) plus image_width / image_height, optionally split over an intrinsics and an
// extrinsics file, optionally with *_sigma entries. docs/camera-model.md describes the format.

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon {

// Thrown for a file that cannot be used; what() names the file, the key and the problem.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A calibration's text and the name its errors give it (the file it came from).
struct CalibrationText {
  std::string name;
  std::string text;
};

// The rig that the texts hold together, as load_rig reads it from files (the same rules, the same
// errors): the reader of what has already been read, from a file, a pipe or a fuzzer.
StereoRig parse_rig(const std::vector<CalibrationText>& texts);

// The same without throwing: the rig, or what parse_rig's CalibrationError would say. For callers
// to whom a refused calibration is an expected outcome (a fuzzer: a throw costs 10-20 us, most of
// what a refused text takes to read; docs/reliability.md, "Fifth run").
struct RigOrRefusal {
  std::optional<StereoRig> rig;
  std::string refusal;  // set when rig is not
};
RigOrRefusal try_parse_rig(const std::vector<CalibrationText>& texts);

// Reads a rig from one file holding every key, or from several files that together hold them
// (for instance intrinsics.yml + extrinsics.yml). A key given twice with different values is refused.
StereoRig load_rig(const std::vector<std::filesystem::path>& files);
inline StereoRig load_rig(const std::filesystem::path& file) {
  return load_rig(std::vector<std::filesystem::path>{file});
}

// Writes every key (and the sigmas present) to one file.
void save_rig(const StereoRig& rig, const std::filesystem::path& file);

}  // namespace naneye::recon
