#pragma once
// A whole simulated capture on disk: capture.raw (the spec's byte stream) or capture.neyd, and
// truth.json (docs/simulator.md describes every key). What `naneye sim` runs.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "naneye/sim/presets.hpp"
#include "naneye/sim/stream.hpp"

namespace naneye::sim {

enum class CaptureFormat { raw, neyd };

struct CaptureSettings {
  std::string preset = "paper-d3";
  std::filesystem::path calibration;  // empty: the preset's
  int pairs = 12;
  std::uint64_t seed = 1;
  std::filesystem::path out_dir;
  CaptureFormat format = CaptureFormat::raw;
  bool bayer = false;
  bool noise_free = false;     // SensorSettings::ideal() and uniform lighting
  double partial_share = 0.1;  // pairs whose board is partly out of view
  double absent_share = 0.05;  // pairs without a board
  TimingSettings timing;
  FaultSettings faults;
  int supersample = 0;            // edge samples per pixel side; 0: SceneSettings' default
  std::int64_t start_ticks = -1;  // first left timestamp; < 0: drawn from the seed
};

struct CaptureSummary {
  std::filesystem::path stream_file, truth_file;
  std::uint64_t bytes = 0;
  int pairs = 0, full = 0, partial = 0, absent = 0, lost_records = 0;
};

CaptureSummary write_capture(const CaptureSettings& o);

// One pair's truth entry, keys as docs/simulator.md lists them.
nlohmann::json truth_json(const Truth& t, int pair, std::int64_t t_left_ns, std::int64_t t_right_ns);

}  // namespace naneye::sim
