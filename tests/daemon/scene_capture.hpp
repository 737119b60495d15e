#pragma once
// Textured scenes for the daemon's scene tests: pairs rendered through the paper's
// Dataset 3 rig with one sub-sample per pixel (a third of the tests/scene renders' cost: these
// tests check the daemon's plumbing against the truth, not the matcher's last digit).
#include <filesystem>
#include <fstream>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "naneye/driver/frame.hpp"
#include "naneye/driver/wire_format.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::daemon::test {

inline const recon::StereoRig& scene_rig() {
  static const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  return rig;
}

inline const sim::TexturedRenderer& scene_renderer(bool bayer) {
  static const sim::TexturedRenderer mono(scene_rig(), sim::SensorSettings{}, 1);
  static const sim::TexturedRenderer colour(
      scene_rig(),
      [] {
        sim::SensorSettings s;
        s.bayer = true;
        return s;
      }(),
      1);
  return bayer ? colour : mono;
}

// The preset seen from the hand-held camera at time t (s).
inline sim::TexturedSceneSettings scene_at(const std::string& preset, double t) {
  const auto s = *sim::textured_preset(preset);
  return sim::seen_from(s, sim::handheld_camera_pose(s.light_reference_mm, t));
}

// The tests' scene: the sphere (12-20 mm) at pair k of the hand-held trajectory at 62 fps. Rendered
// once per process and shared (a render costs ~0.25 s of CPU), mono and Bayer.
inline constexpr const char* kScenePreset = "sphere";
inline sim::TexturedSceneSettings test_scene(int k) {
  return scene_at(kScenePreset, k / 62.0);
}

inline const std::pair<cv::Mat, cv::Mat>& scene_frames(int k, bool bayer) {
  static std::map<std::pair<int, bool>, std::pair<cv::Mat, cv::Mat>> cache;
  auto it = cache.find({k, bayer});
  if (it == cache.end()) {
    sim::Rng rng(100 + static_cast<std::uint64_t>(k));
    std::pair<cv::Mat, cv::Mat> f;
    scene_renderer(bayer).render_frames(test_scene(k), rng, f.first, f.second);
    it = cache.emplace(std::make_pair(k, bayer), std::move(f)).first;
  }
  return it->second;
}

// Pair k of the tests' scene as the driver delivers it.
inline driver::StereoPair scene_pair(int k, bool bayer) {
  const auto& f = scene_frames(k, bayer);
  driver::StereoPair p;
  p.index = static_cast<std::uint64_t>(k);
  p.left.sensor_ns = static_cast<std::int64_t>(k) * 16'000'000;
  p.right.sensor_ns = p.left.sensor_ns + 2'000'000;
  p.right.sensor = driver::Sensor::right;
  p.left.color = p.right.color = bayer ? driver::ColorMode::bayer_grbg : driver::ColorMode::mono;
  std::copy_n(f.first.ptr<std::uint16_t>(), driver::kPixelCount, p.left.pixels.begin());
  std::copy_n(f.second.ptr<std::uint16_t>(), driver::kPixelCount, p.right.pixels.begin());
  return p;
}

// A mono capture file of the tests' scene's first `pairs` pairs (62 fps, the right 2.5 ms after
// the left); pair k is scene_pair(k) and test_scene(k) its truth.
inline void write_scene_capture(const std::filesystem::path& file, int pairs) {
  std::ofstream out(file, std::ios::binary);
  std::vector<std::uint8_t> rec(driver::kRecordSize);
  std::uint8_t seq = 0;
  const std::uint32_t period = driver::kTickHz / 62, offset = 120'000;
  for (int k = 0; k < pairs; ++k)
    for (int sensor = 0; sensor < 2; ++sensor) {
      const cv::Mat& m = sensor == 0 ? scene_frames(k, false).first : scene_frames(k, false).second;
      const driver::RecordHeader h{seq++, sensor == 0 ? driver::Sensor::left : driver::Sensor::right,
                                   1000 + static_cast<std::uint32_t>(k) * period + (sensor ? offset : 0)};
      driver::encode_record(
          h, std::span<const std::uint16_t, driver::kPixelCount>(m.ptr<std::uint16_t>(), driver::kPixelCount),
          std::span<std::uint8_t, driver::kRecordSize>(rec.data(), driver::kRecordSize));
      out.write(reinterpret_cast<const char*>(rec.data()), static_cast<std::streamsize>(rec.size()));
    }
}

}  // namespace naneye::daemon::test
