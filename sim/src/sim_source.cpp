// The live simulator source: render, encode, feed the driver's byte-stream path, pace to the clock.
#include "naneye/sim/sim_source.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <vector>

#include "log.hpp"
#include "naneye/base/clock.hpp"
#include "naneye/base/enum_table.hpp"
#include "naneye/driver/replay_clock.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/flat_field.hpp"
#include "naneye/sim/stream.hpp"

namespace naneye::sim {
namespace {

constexpr base::EnumTable<Motion, 4> kMotionNames{{{Motion::orbit, "orbit"},
                                                   {Motion::sweep, "sweep"},
                                                   {Motion::still, "still"},
                                                   {Motion::handheld, "handheld"}}};

template <typename T>
T number(const driver::SourceUri& uri, const char* name, T fallback, T lo, T hi) {
  const auto v = uri.param(name);
  if (!v) return fallback;
  T out{};
  const auto [end, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || end != v->data() + v->size() || out < lo || out > hi)
    throw driver::SourceError("sim: parameter " + std::string(name) + "=" + *v + " is not a number in [" +
                              std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return out;
}

bool flag(const driver::SourceUri& uri, const char* name, bool fallback) {
  const auto v = uri.param(name);
  if (!v) return fallback;
  if (*v == "1" || *v == "true") return true;
  if (*v == "0" || *v == "false") return false;
  throw driver::SourceError("sim: parameter " + std::string(name) + "=" + *v + " must be 0 or 1");
}

}  // namespace

SimSourceSettings parse_sim_uri(const driver::SourceUri& uri) {
  uri.allow_only({"fps", "motion", "seed", "bayer", "noise", "pairs", "speed", "color", "tolerance_ms",
                  "reference", "supersample", "sensor"});
  SimSourceSettings o;
  o.preset = uri.target.empty() ? "paper-d3" : uri.target;
  o.textured = textured_preset(o.preset).has_value();
  // The flat's light: 0.7 of white, ~530 DN at the default exposure, clear of saturation.
  if (o.preset == "dark" || o.preset == "flat") o.calibration_light = o.preset == "dark" ? 0.0 : 0.7;
  if (!o.textured && o.calibration_light < 0 && !find_preset(o.preset))
    throw driver::SourceError(
        "sim: unknown preset '" + o.preset +
        "' (paper-d1, paper-d2, paper-d3; plane, plane-far, sphere, tube, height; dark, flat)");
  if (const auto v = uri.param("sensor")) {
    if (*v != "default" && *v != "measured")
      throw driver::SourceError("sim: sensor=" + *v + " (default, measured)");
    o.measured_sensor = *v == "measured";
  }
  if (o.calibration_light >= 0 && uri.param("motion"))
    throw driver::SourceError("sim: " + o.preset +
                              " frames have no motion (the lens capped or the target filling it)");
  // A textured scene's default rate is what its renderer holds in real time (sim_source.hpp).
  o.fps = o.textured ? number(uri, "fps", 10.0, 1.0, 62.0) : number(uri, "fps", 50.0, 43.0, 62.0);
  o.motion = o.textured ? Motion::handheld : Motion::orbit;
  if (!o.textured && uri.param("supersample"))
    throw driver::SourceError("sim: supersample is for the textured scenes only");
  o.supersample = number(uri, "supersample", 1, 1, 3);
  if (const auto m = uri.param("motion")) {
    if (const auto motion = base::enum_parse(kMotionNames, *m))
      o.motion = *motion;
    else
      throw driver::SourceError("sim: motion=" + *m + " (" + base::enum_names(kMotionNames) + ")");
    // Each trajectory belongs to one kind of scene: a board orbits or sweeps, a hand holds the
    // camera over a textured surface (or keeps it still).
    if (o.textured != (o.motion == Motion::handheld) && o.motion != Motion::still)
      throw driver::SourceError("sim: motion=" + *m +
                                (o.textured ? " is for the board presets" : " is for the textured scenes"));
  }
  o.seed = number<std::uint64_t>(uri, "seed", 1, 0, UINT64_MAX);
  o.bayer = flag(uri, "bayer", false);
  o.noise = flag(uri, "noise", true);
  if (o.measured_sensor && !o.noise)
    throw driver::SourceError("sim: sensor=measured has noise: noise=0 is the ideal sensor");
  o.pairs = number<std::uint64_t>(uri, "pairs", 0, 0, UINT64_MAX);
  if (const auto s = uri.param("speed")) {
    if (*s != "realtime" && *s != "max") throw driver::SourceError("sim: speed=" + *s + " (realtime, max)");
    o.realtime = *s == "realtime";
  }
  driver::StreamSettings defaults;
  defaults.parser.color = o.bayer ? driver::ColorMode::bayer_grbg : driver::ColorMode::mono;
  o.stream = driver::parse_stream_params(uri, defaults);
  return o;
}

Pose trajectory_pose(Motion m, const BoardGeometry& board, double distance_mm, double t) {
  const double two_pi = 2.0 * M_PI, deg = M_PI / 180.0;
  double z = distance_mm, tilt = 0, axis = 0, roll = 0;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();  // normalized
  switch (m) {
    case Motion::orbit:  // the centre circles the axis while the board wobbles: every tilt direction
      z = distance_mm * (1.0 + 0.08 * std::sin(two_pi * t / 7.0));
      offset = 0.06 * Eigen::Vector2d(std::cos(two_pi * t / 5.0), std::sin(two_pi * t / 5.0));
      tilt = 25 * deg;
      axis = two_pi * t / 5.0 + M_PI / 2;
      roll = 10 * deg * std::sin(two_pi * t / 11.0);
      break;
    case Motion::sweep:  // towards and away from the cameras
      z = distance_mm * (1.02 + 0.16 * std::sin(two_pi * t / 6.0));
      tilt = 15 * deg;
      axis = 0.3;
      break;
    case Motion::still:
    case Motion::handheld:  // a board is not held by hand here: treated as still
      tilt = 20 * deg;
      axis = 0.5;
      break;
  }
  Pose p;
  p.R = (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(axis), std::sin(axis), 0)) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
  p.t = Eigen::Vector3d(offset.x() * z, offset.y() * z, z) - p.R * board.centre();
  return p;
}

SimSource::SimSource(SimSourceSettings options, std::string uri_text)
    : driver::ByteStreamSource(driver::SourceInfo{uri_text.empty() ? "sim://" + options.preset : uri_text,
                                                  "sim", options.preset, options.realtime, options.fps},
                               options.stream),
      options_(std::move(options)) {}

SimSource::~SimSource() {
  stop();
}

void SimSource::open() {
  if (options_.textured) {
    // The textured scenes are rendered through the paper's Dataset 3 rig, as in tests/scene.
    recon::StereoRig rig;
    try {
      rig = recon::load_rig(find_calibration("paper-d3.yaml"));
    } catch (const std::exception& e) {
      throw driver::SourceError(std::string("sim: ") + e.what());
    }
    textured_ = std::make_unique<TexturedRenderer>(rig, sensor_settings(), options_.supersample);
    return;
  }
  if (options_.calibration_light >= 0) {
    calibration_ = std::make_unique<SensorModel>(sensor_settings());
    return;
  }
  const Preset preset = *find_preset(options_.preset);
  recon::StereoRig rig;
  try {
    rig = recon::load_rig(find_calibration(preset.calib_file));
  } catch (const std::exception& e) {
    throw driver::SourceError(std::string("sim: ") + e.what());
  }
  SceneSettings scene = preset_scene(preset);
  if (!options_.noise) scene.lighting = false;
  renderer_ = std::make_unique<Renderer>(rig, scene, sensor_settings());
}

SensorSettings SimSource::sensor_settings() const {
  SensorSettings s = options_.measured_sensor ? SensorSettings::measured(options_.bayer)
                                              : (options_.noise ? SensorSettings{} : SensorSettings::ideal());
  s.bayer = options_.bayer;
  return s;
}

void SimSource::run() {
  Rng rng(options_.seed);
  TimingSettings timing;
  timing.fps_start = options_.fps;
  if (options_.calibration_light >= 0) {
    log()->info("sim://{}: {} fps, calibration frames", options_.preset, options_.fps);
    SensorModel::Scratch scratch;
    cv::Mat frame;
    return stream(timing, rng, [&](Rng& r, double, std::uint16_t* left, std::uint16_t* right) {
      for (int eye = 0; eye < 2; ++eye) {
        expose_calibration_frame(*calibration_, eye, options_.calibration_light, r, scratch, frame);
        std::copy_n(frame.ptr<std::uint16_t>(), driver::kPixelCount, eye == 0 ? left : right);
      }
    });
  }
  if (options_.textured) {
    const TexturedSceneSettings scene = *textured_preset(options_.preset);
    // The simulated sensors run at the chosen rate (sim_source.hpp: below 43 fps for textured scenes).
    timing.fps_min = std::min(timing.fps_min, options_.fps);
    timing.fps_max = std::max(options_.fps, std::min(timing.fps_max, options_.fps * 1.2));
    timing.fps_step = std::min(timing.fps_step, 0.005 * options_.fps);
    log()->info("sim://{}: textured scene, {} fps, camera {}", options_.preset, options_.fps,
                options_.motion == Motion::handheld ? "hand-held" : "still");
    cv::Mat l, r;
    return stream(timing, rng, [&](Rng& g, double t, std::uint16_t* left, std::uint16_t* right) {
      Pose camera;  // still: where the preset puts it
      camera.t.setZero();
      // The scale of the motion: the preset's own reference distance (10-55 mm).
      if (options_.motion == Motion::handheld) camera = handheld_camera_pose(scene.light_reference_mm, t);
      textured_->render_frames(seen_from(scene, camera), g, l, r);
      std::copy_n(l.ptr<std::uint16_t>(), driver::kPixelCount, left);
      std::copy_n(r.ptr<std::uint16_t>(), driver::kPixelCount, right);
    });
  }
  const Preset preset = *find_preset(options_.preset);
  Renderer::Scratch scratch;
  log()->info("sim://{}: {} fps, rendering", options_.preset, options_.fps);
  stream(timing, rng, [&](Rng& g, double t, std::uint16_t* left, std::uint16_t* right) {
    renderer_->render_into(trajectory_pose(options_.motion, renderer_->scene().board, preset.distance_mm, t),
                           g, left, right, scratch);
  });
}

void SimSource::stream(const TimingSettings& timing, Rng& rng, const RenderPair& render) {
  const std::uint64_t start_ticks = rng() % (std::uint64_t{1} << 32);
  FrameClock clock(timing, start_ticks, rng);
  RecordWriter writer(
      [this](std::span<const std::uint8_t> b, std::int64_t) { feed(b, base::monotonic_ns()); }, {}, 0,
      static_cast<std::uint8_t>(rng()));
  std::vector<std::uint16_t> left(driver::kPixelCount), right(driver::kPixelCount);
  driver::ReplayClock pace;  // the camera's spacing; a held or slow render goes on from its late record
  std::uint64_t resyncs = 0;
  for (std::uint64_t i = 0; options_.pairs == 0 || i < options_.pairs; ++i) {
    if (stopping()) return;
    const PairTime pt = clock.next(rng);
    render(rng, static_cast<double>(pt.left_ticks - start_ticks) / driver::kTickHz, left.data(),
           right.data());
    // A record is complete when its frame has been read out: pace each to its sensor time.
    for (int eye = 0; eye < 2; ++eye) {
      const std::uint64_t ticks = eye == 0 ? pt.left_ticks : pt.right_ticks;
      if (options_.realtime) {
        const auto due = pace.due(
            static_cast<std::int64_t>(static_cast<double>(ticks - start_ticks) * 1e9 / driver::kTickHz),
            std::chrono::steady_clock::now());
        if (pace.resyncs() != resyncs) {
          if (resyncs % 100 == 0)
            log()->warn(
                "sim://{}: a record more than {} ms late (rendering slower than {} fps, or the "
                "machine held it): pairs go on from it at the camera's spacing",
                options_.preset, driver::ReplayClock::kHeldAfter.count(), options_.fps);
          resyncs = pace.resyncs();
        }
        if (!sleep_until(due)) return;
      }
      writer.write(eye == 0 ? driver::Sensor::left : driver::Sensor::right, static_cast<std::uint32_t>(ticks),
                   std::span<const std::uint16_t, driver::kPixelCount>((eye == 0 ? left : right).data(),
                                                                       driver::kPixelCount),
                   0);
      writer.finish();  // hand the record over now: a live source never holds one back
    }
  }
  end_of_stream(base::monotonic_ns());
}

void register_sim_source(driver::SourceRegistry& registry) {
  registry.add("sim", [](const driver::SourceUri& uri) -> std::unique_ptr<driver::FrameSource> {
    return std::make_unique<SimSource>(parse_sim_uri(uri), uri.text);
  });
}

}  // namespace naneye::sim
