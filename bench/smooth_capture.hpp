#pragma once
// A temporally smooth capture for the benchmarks: the simulator's "orbit" trajectory (sim_source.hpp)
// at the paper's Dataset 3 distance, one pair every 1/62 s, rendered with the default noisy sensor and
// written as the spec's byte stream (.raw). Played forwards then backwards, so that a looping replay
// never jumps: the tracker sees a smooth motion throughout. Written at bench start, never committed.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "naneye/driver/wire_format.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/presets.hpp"
#include "naneye/sim/render.hpp"
#include "naneye/sim/sim_source.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::bench {

// Writes the frames forwards then back (2 * n - 2 pairs) at `fps`; returns the pairs written.
inline int write_forwards_back(const std::filesystem::path& file,
                               const std::vector<std::pair<cv::Mat, cv::Mat>>& frames, double fps) {
  const int pairs = static_cast<int>(frames.size());
  std::vector<int> order;
  for (int k = 0; k < pairs; ++k) order.push_back(k);
  for (int k = pairs - 2; k >= 1; --k) order.push_back(k);

  const auto period = static_cast<std::uint32_t>(static_cast<double>(driver::kTickHz) / fps + 0.5);
  const std::uint32_t offset = 120'000;  // right 2.5 ms after left
  std::ofstream out(file, std::ios::binary);
  std::vector<std::uint8_t> rec(driver::kRecordSize);
  std::uint8_t seq = 0;
  std::uint32_t ticks = 1000;
  for (const int k : order) {
    for (int sensor = 0; sensor < 2; ++sensor) {
      const cv::Mat& img = sensor == 0 ? frames[static_cast<std::size_t>(k)].first
                                       : frames[static_cast<std::size_t>(k)].second;
      const driver::RecordHeader h{seq++, sensor == 0 ? driver::Sensor::left : driver::Sensor::right,
                                   ticks + (sensor ? offset : 0)};
      driver::encode_record(
          h,
          std::span<const std::uint16_t, driver::kPixelCount>(img.ptr<std::uint16_t>(), driver::kPixelCount),
          std::span<std::uint8_t, driver::kRecordSize>(rec.data(), driver::kRecordSize));
      out.write(reinterpret_cast<const char*>(rec.data()), static_cast<std::streamsize>(rec.size()));
    }
    ticks += period;
  }
  return static_cast<int>(order.size());
}

// Renders `pairs` poses and writes 2 * pairs - 2 records pairs (forwards, then back). Returns the
// number of pairs written.
inline int write_smooth_capture(const std::filesystem::path& file, int pairs, double fps = 62.0) {
  const sim::Preset preset = *sim::find_preset("paper-d3");
  const recon::StereoRig rig = recon::load_rig(sim::find_calibration(preset.calib_file));
  const sim::SceneSettings scene = sim::preset_scene(preset);
  const sim::Renderer renderer(rig, scene, sim::SensorSettings{});
  sim::Rng rng(62);
  std::vector<sim::RenderedPair> frames;
  for (int k = 0; k < pairs; ++k)
    frames.push_back(renderer.render(
        sim::trajectory_pose(sim::Motion::orbit, scene.board, preset.distance_mm, k / fps), rng));
  std::vector<std::pair<cv::Mat, cv::Mat>> lr;
  for (auto& f : frames) lr.emplace_back(f.left, f.right);
  return write_forwards_back(file, lr, fps);
}

// The same for a textured scene (sim/textured.hpp) seen from the hand-held camera, rendered with
// one sub-sample per pixel (the benchmark times the daemon, not the renderer's anti-aliasing).
inline int write_scene_capture(const std::filesystem::path& file, const std::string& preset, int pairs,
                               double fps = 62.0) {
  const recon::StereoRig rig = recon::load_rig(sim::find_calibration("paper-d3.yaml"));
  const sim::TexturedRenderer renderer(rig, sim::SensorSettings{}, 1);
  const sim::TexturedSceneSettings scene = *sim::textured_preset(preset);
  sim::Rng rng(62);
  std::vector<std::pair<cv::Mat, cv::Mat>> frames(static_cast<std::size_t>(pairs));
  for (int k = 0; k < pairs; ++k)
    renderer.render_frames(
        sim::seen_from(scene, sim::handheld_camera_pose(scene.light_reference_mm, k / fps)), rng,
        frames[static_cast<std::size_t>(k)].first, frames[static_cast<std::size_t>(k)].second);
  return write_forwards_back(file, frames, fps);
}

}  // namespace naneye::bench
