#pragma once
// sim://PRESET?fps=50&motion=orbit: a live FrameSource rendering a board on a smooth trajectory in
// its own thread. The pairs take the real driver path: records are encoded to the spec's bytes and
// fed to driver::ByteStreamSource (parser -> pairer -> pool -> lock-free ring -> next()), so the
// counters, the raw tap (naneye record) and the hand-over behave exactly as with a camera.
//
//   sim://paper-d1|paper-d2|paper-d3            the paper's board
//   sim://plane|plane-far|sphere|tube|height     a textured scene (textured.hpp), seen by a camera
//                                                held by hand (motion=handheld, the default there)
//   sim://dark|flat                              the sensor's calibration frames (flat_field.hpp):
//                                                the lens capped, a uniform white target (0.7 of
//                                                white); for `naneye fixed-pattern`
//     ?fps=<43..62>           nominal frame rate (drifts within 43-62 fps, as the sensors do); a
//                             textured scene takes 1..62 and defaults to 10: its renderer manages
//                             ~10-20 pairs/s on one core, and a camera rate it cannot hold would
//                             be a number the stream does not have (speed=max: as fast as it renders)
//     &motion=orbit|sweep|still|handheld
//     &supersample=1..3       textured scenes: sub-samples per pixel side (default 1; 3 as the tests)
//     &seed=<n>               noise and timing; the same seed gives the same pairs
//     &bayer=0|1  &noise=0|1  (noise=0: ideal sensor, uniform light)
//     &sensor=default|measured  measured: the real NanEye's blur, noise and fixed pattern
//                             (SensorSettings::measured, docs/simulator.md)
//     &pairs=<n>              stop after n pairs (0: endless)
//     &speed=realtime|max     max: render as fast as possible, lossless hand-over
//   plus the stream parameters of every byte-stream source (color, tolerance_ms, reference).
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "naneye/driver/byte_stream_source.hpp"
#include "naneye/driver/source_registry.hpp"
#include "naneye/driver/source_uri.hpp"
#include "naneye/sim/presets.hpp"
#include "naneye/sim/sensor_model.hpp"
#include "naneye/sim/stream.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::sim {

enum class Motion { orbit, sweep, still, handheld };

struct SimSourceSettings {
  std::string preset = "paper-d3";
  double fps = 50;
  Motion motion = Motion::orbit;
  std::uint64_t seed = 1;
  bool bayer = false;
  bool noise = true;
  std::uint64_t pairs = 0;
  bool realtime = true;
  driver::StreamSettings stream;
  bool textured = false;  // preset is a textured scene (textured_preset), not a board
  int supersample = 1;
  bool measured_sensor = false;
  // >= 0: the preset is a calibration target (dark 0, flat 0.7 of white), not a board or a scene.
  double calibration_light = -1;
};

SimSourceSettings parse_sim_uri(const driver::SourceUri& uri);

// The board pose at time t (s) on a trajectory around the preset's distance.
Pose trajectory_pose(Motion m, const BoardGeometry& board, double distance_mm, double t);

class SimSource : public driver::ByteStreamSource {
 public:
  explicit SimSource(SimSourceSettings options, std::string uri_text = {});
  ~SimSource() override;

 protected:
  void open() override;
  void run() override;

 private:
  // The one pacing loop: per pair, `render(rng, t, left, right)` fills both frames for sensor time
  // t (s); the records are paced to the sensors' clock (realtime) and fed to the byte-stream path.
  using RenderPair = std::function<void(Rng&, double t, std::uint16_t* left, std::uint16_t* right)>;
  void stream(const TimingSettings& timing, Rng& rng, const RenderPair& render);
  SensorSettings sensor_settings() const;

  SimSourceSettings options_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<TexturedRenderer> textured_;
  std::unique_ptr<SensorModel> calibration_;
};

// Adds the "sim" scheme to a registry.
void register_sim_source(driver::SourceRegistry& registry);

}  // namespace naneye::sim
