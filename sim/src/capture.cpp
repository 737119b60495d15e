// `naneye sim`: random poses of a preset, rendered pair by pair into the record stream, with truth.
#include "naneye/sim/capture.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "log.hpp"
#include "naneye/driver/neyd.hpp"
#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye::sim {
namespace {

nlohmann::json vec(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

nlohmann::json pixels(const std::vector<Eigen::Vector2d>& px, const std::vector<bool>& imaged) {
  nlohmann::json a = nlohmann::json::array();
  for (std::size_t k = 0; k < px.size(); ++k)
    a.push_back(imaged[k] ? nlohmann::json{px[k].x(), px[k].y()} : nlohmann::json(nullptr));
  return a;
}

std::int64_t ticks_to_ns(std::uint64_t ticks) {
  return static_cast<std::int64_t>(std::llround(static_cast<double>(ticks) * 1e9 / driver::kTickHz));
}

}  // namespace

nlohmann::json truth_json(const Truth& t, int pair, std::int64_t t_left_ns, std::int64_t t_right_ns) {
  nlohmann::json j;
  j["pair"] = pair;
  j["t_left_ns"] = t_left_ns;
  j["t_right_ns"] = t_right_ns;
  j["board_in_view"] = t.board_in_view;
  j["board_present"] = t.board_present;
  const auto& R = t.pose.R;
  j["board_rotation"] = {
      {R(0, 0), R(0, 1), R(0, 2)}, {R(1, 0), R(1, 1), R(1, 2)}, {R(2, 0), R(2, 1), R(2, 2)}};
  j["board_translation_mm"] = vec(t.pose.t);
  nlohmann::json xyz = nlohmann::json::array();
  for (const auto& X : t.corners_mm) xyz.push_back(vec(X));
  j["corners_xyz_mm"] = xyz;
  j["left_px"] = pixels(t.left_px, t.left_imaged);
  j["right_px"] = pixels(t.right_px, t.right_imaged);
  j["left_in_view"] = t.left_in_view;
  j["right_in_view"] = t.right_in_view;
  return j;
}

CaptureSummary write_capture(const CaptureSettings& o) {
  const auto preset = find_preset(o.preset);
  if (!preset)
    throw std::invalid_argument("sim: unknown preset '" + o.preset + "' (paper-d1, paper-d2, paper-d3)");
  if (o.pairs < 1) throw std::invalid_argument("sim: --pairs must be at least 1");
  const std::filesystem::path calib =
      o.calibration.empty() ? find_calibration(preset->calib_file) : o.calibration;
  const recon::StereoRig rig = recon::load_rig(calib);

  SceneSettings scene = preset_scene(*preset);
  SensorSettings sensor = o.noise_free ? SensorSettings::ideal() : SensorSettings{};
  if (o.noise_free) scene.lighting = false;
  if (o.supersample > 0) scene.supersample = o.supersample;
  sensor.bayer = o.bayer;
  const Renderer renderer(rig, scene, sensor);

  PoseSettings ps;
  ps.distance_mm = preset->distance_mm;
  Rng rng(o.seed);
  const std::uint64_t start =
      o.start_ticks >= 0 ? static_cast<std::uint64_t>(o.start_ticks) : rng() % (std::uint64_t{1} << 32);
  FrameClock clock(o.timing, start, rng);

  std::filesystem::create_directories(o.out_dir);
  CaptureSummary sum;
  sum.stream_file = o.out_dir / (o.format == CaptureFormat::raw ? "capture.raw" : "capture.neyd");
  sum.truth_file = o.out_dir / "truth.json";
  // Host arrival times are simulated too (a fixed origin plus sensor time plus the readout), so
  // that the same seed gives the same bytes in either format.
  constexpr std::int64_t kHostOrigin = 1'000'000'000, kReadoutNs = 2'000'000;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> raw(nullptr, &std::fclose);
  std::unique_ptr<driver::NeydWriter> neyd;
  ByteSink sink;
  if (o.format == CaptureFormat::raw) {
    raw.reset(std::fopen(sum.stream_file.c_str(), "wb"));
    if (!raw) throw std::runtime_error("sim: cannot write " + sum.stream_file.string());
    sink = [&](std::span<const std::uint8_t> b, std::int64_t) {
      if (std::fwrite(b.data(), 1, b.size(), raw.get()) != b.size())
        throw std::runtime_error("sim: write error on " + sum.stream_file.string());
    };
  } else {
    driver::NeydHeader h;
    h.start_monotonic_ns = kHostOrigin;
    h.note = nlohmann::json{{"source", "naneye sim"}, {"preset", preset->name}, {"seed", o.seed}}.dump();
    neyd = std::make_unique<driver::NeydWriter>(sum.stream_file.string(), h);
    sink = [&](std::span<const std::uint8_t> b, std::int64_t host_ns) { neyd->write_chunk(b, host_ns); };
  }
  RecordWriter out(sink, o.faults, o.seed ^ 0x9e3779b97f4a7c15ULL, static_cast<std::uint8_t>(rng()));

  nlohmann::json truth;
  truth["square_mm"] = scene.board.square_mm;
  truth["pattern"] = {scene.board.rows, scene.board.cols};
  truth["preset"] = preset->name;
  truth["calibration"] = calib.filename().string();
  truth["seed"] = o.seed;
  truth["bayer"] = o.bayer;
  truth["noise_free"] = o.noise_free;
  truth["start_ticks"] = start;
  truth["pairs"] = nlohmann::json::array();

  Renderer::Scratch scratch;
  std::vector<std::uint16_t> left(driver::kPixelCount), right(driver::kPixelCount);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int i = 0; i < o.pairs; ++i) {
    const double kind = u01(rng);
    const bool absent = kind < o.absent_share;
    const bool partial = !absent && kind < o.absent_share + o.partial_share;
    const Pose pose = partial ? sample_partial_pose(rig, scene.board, ps, rng)
                              : sample_full_pose(rig, scene.board, ps, rng);
    if (absent)
      renderer.render_background_into(rng, left.data(), right.data(), scratch);
    else
      renderer.render_into(pose, rng, left.data(), right.data(), scratch);
    const Truth t = compute_truth(rig, scene.board, pose, !absent);
    sum.absent += absent;
    sum.partial += partial;
    sum.full += t.board_in_view;

    const PairTime pt = clock.next(rng);
    const std::int64_t tl = ticks_to_ns(pt.left_ticks - start), tr = ticks_to_ns(pt.right_ticks - start);
    const RecordFate fl =
        out.write(driver::Sensor::left, static_cast<std::uint32_t>(pt.left_ticks),
                  std::span<const std::uint16_t, driver::kPixelCount>(left.data(), driver::kPixelCount),
                  kHostOrigin + tl + kReadoutNs);
    const RecordFate fr =
        out.write(driver::Sensor::right, static_cast<std::uint32_t>(pt.right_ticks),
                  std::span<const std::uint16_t, driver::kPixelCount>(right.data(), driver::kPixelCount),
                  kHostOrigin + tr + kReadoutNs);
    nlohmann::json j = truth_json(t, i, tl, tr);
    j["t_left_ticks"] = static_cast<std::uint32_t>(pt.left_ticks);
    j["t_right_ticks"] = static_cast<std::uint32_t>(pt.right_ticks);
    if (o.faults.any()) {
      j["left_lost"] = fl.lost;
      j["right_lost"] = fr.lost;
      j["damaged_bytes"] = fl.bit_flips + fl.dropped_bytes + fr.bit_flips + fr.dropped_bytes;
    }
    sum.lost_records += fl.lost + fr.lost;
    truth["pairs"].push_back(std::move(j));
  }
  sum.bytes = out.finish();
  if (raw && std::fclose(raw.release()) != 0)
    throw std::runtime_error("sim: cannot close " + sum.stream_file.string());
  if (neyd) neyd->close();
  sum.pairs = o.pairs;
  if (o.faults.any()) {
    truth["faults"] = {{"bit_flip_rate", o.faults.bit_flip_rate},
                       {"dropped_byte_rate", o.faults.dropped_byte_rate},
                       {"lost_record_rate", o.faults.lost_record_rate},
                       {"truncate_tail", o.faults.truncate_tail}};
  }
  // One pair per line: diffable, and small enough to bundle.
  std::ofstream tf(sum.truth_file);
  nlohmann::json head = truth;
  head.erase("pairs");
  std::string h = head.dump();
  h.pop_back();  // reopen the object to append the pairs
  tf << h << ",\n\"pairs\": [\n";
  for (std::size_t i = 0; i < truth["pairs"].size(); ++i)
    tf << truth["pairs"][i].dump() << (i + 1 < truth["pairs"].size() ? ",\n" : "\n");
  tf << "]}\n";
  if (!tf) throw std::runtime_error("sim: cannot write " + sum.truth_file.string());
  log()->info("{}: {} pairs ({} full, {} partial, {} absent), {} bytes", sum.stream_file.string(), sum.pairs,
              sum.full, sum.partial, sum.absent, sum.bytes);
  return sum;
}

}  // namespace naneye::sim
