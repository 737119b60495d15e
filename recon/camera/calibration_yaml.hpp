#pragma once
// Reads one calibration file, the YAML that OpenCV's FileStorage writes, with libyaml (yaml_tree.hpp):
// OpenCV 4.6's own reader looped forever on a 247-byte file the fuzzer wrote (docs/reliability.md), and a
// calibration is read again on every SIGHUP. Private to recon/camera (calibration_io.cpp).

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace naneye::recon::detail {

// One top-level key. A number is a 1x1 matrix; an `!!opencv-matrix` (rows, cols, dt, data) its
// matrix; both CV_64F. Any other value (a string, a sequence, a map without data) is not ours and
// keeps `value` empty, with `skipped` saying what it was, so that a key we need can be named.
struct YamlKey {
  std::string key;
  cv::Mat value;
  std::string skipped;
};

// Every top-level key in file order (a key given twice comes twice). Throws CalibrationError naming
// the file (and the line, or the key) for a file that is not such a YAML.
std::vector<YamlKey> read_calibration_yaml(const std::filesystem::path& path);

}  // namespace naneye::recon::detail
