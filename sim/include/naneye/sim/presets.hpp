#pragma once
// The paper's three calibration datasets as presets (Dias et al., ICDSC 2016, Sec. 4: 9 x 7 squares,
// 2.25 mm at ~20 mm, 4.50 mm at ~50 mm, 5.99 mm at ~70 mm), and the random board poses they use.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {

struct Preset {
  std::string name;        // "paper-d1" ...
  std::string calib_file;  // file name under config/calib
  double square_mm = 0;
  double distance_mm = 0;  // average board distance of the dataset
};

const std::vector<Preset>& presets();
std::optional<Preset> find_preset(std::string_view name);
// The calibration of a preset: config/calib/<file> of the installed data directory, the source tree
// this was built from, or ./config/calib, first found. Throws std::runtime_error when none has it.
std::filesystem::path find_calibration(const std::string& file);
// The scene of a preset: its board, lit for its distance.
SceneSettings preset_scene(const Preset& p);

// How random poses are drawn (docs/simulator.md).
struct PoseSettings {
  double distance_mm = 70;
  double distance_min = 0.85, distance_max = 1.2;  // relative to distance_mm
  double max_tilt_deg = 40;                        // board normal vs. optical axis
  double max_roll_deg = 25;                        // in-plane rotation
  double max_offset = 0.12;                        // board centre off axis, normalized units
  double margin_px = 6;                            // inner corners keep this far from the image edges
  double fold_margin = 0.95;                       // ... and inside this share of the fold radius
};

// A pose whose inner corners all lie inside both images (with the margin) and well inside both valid
// domains. Throws std::runtime_error if the rig cannot see the board that way.
Pose sample_full_pose(const recon::StereoRig& rig, const BoardGeometry& board, const PoseSettings& s,
                      Rng& rng);
// A full pose slid sideways until only some inner corners remain in view in one image or both.
Pose sample_partial_pose(const recon::StereoRig& rig, const BoardGeometry& board, const PoseSettings& s,
                         Rng& rng);
// True when every inner corner keeps the margins of `s` in both images.
bool pose_fully_visible(const recon::StereoRig& rig, const BoardGeometry& board, const Pose& pose,
                        const PoseSettings& s);

}  // namespace naneye::sim
