#pragma once
// Reads one calibration file, the YAML that OpenCV's FileStorage writes, with libyaml (yaml_tree.hpp):
// OpenCV 4.6's own reader looped forever on a 247-byte file the fuzzer wrote (docs/reliability.md), and a
// calibration is read again on every SIGHUP. Private to recon/camera (calibration_io.cpp).

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
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

// A calibration is a few kB (config/calib/paper-d3.yaml: 2.3 kB, with sigmas and comments); 1 MiB
// is far beyond any, and bounds the text, and so the nodes, that the parser builds for a file that is
// something else.
constexpr std::size_t kMaxCalibrationBytes = std::size_t{1} << 20;

// Why a text was refused: one message naming the file (and the line, or the key), what
// CalibrationError::what() says. Returned, not thrown: most texts a fuzzer or a careless reload
// gives are refused, and a throw costs 10-20 us (docs/reliability.md, "Fifth run").
struct Refusal {
  std::string message;
};

// Every top-level key of `text` in its order (a key given twice comes twice), or nullopt with `r`
// saying why for a text that is not such a YAML.
std::optional<std::vector<YamlKey>> read_calibration_yaml(const std::string& file, std::string_view text,
                                                          Refusal& r);

}  // namespace naneye::recon::detail
