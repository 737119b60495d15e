// Stereo pair rendering cost at default quality (issue 4: <= 50 ms per pair on one core, so that
// sim:// keeps camera rate). Prints ms per pair for each preset and for the steps apart.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/core.hpp>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/presets.hpp"
#include "naneye/sim/render.hpp"

namespace {

using namespace naneye;

struct Setup {
  recon::StereoRig rig;
  sim::SceneSettings scene;
  sim::PoseSettings poses;
  explicit Setup(const char* name) {
    const auto preset = *sim::find_preset(name);
    rig = recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib" / preset.calib_file);
    scene = sim::preset_scene(preset);
    poses.distance_mm = preset.distance_mm;
  }
};

void BM_RenderPair(benchmark::State& state, const char* preset, bool bayer) {
  const Setup s(preset);
  sim::SensorSettings sensor;
  sensor.bayer = bayer;
  const sim::Renderer r(s.rig, s.scene, sensor);
  sim::Rng rng(3);
  std::vector<sim::Pose> poses;
  for (int i = 0; i < 16; ++i) poses.push_back(sim::sample_full_pose(s.rig, s.scene.board, s.poses, rng));
  std::vector<std::uint16_t> left(250 * 250), right(250 * 250);
  sim::Renderer::Scratch scratch;
  std::size_t i = 0;
  for (auto _ : state) {
    r.render_into(poses[i++ % poses.size()], rng, left.data(), right.data(), scratch);
    benchmark::DoNotOptimize(left.data());
    benchmark::DoNotOptimize(right.data());
  }
  state.counters["pairs_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Irradiance(benchmark::State& state) {
  const Setup s("paper-d3");
  const sim::Renderer r(s.rig, s.scene, sim::SensorSettings{});
  sim::Rng rng(3);
  const sim::Pose pose = sim::sample_full_pose(s.rig, s.scene.board, s.poses, rng);
  for (auto _ : state) benchmark::DoNotOptimize(r.irradiance(sim::Eye::left, pose));
  state.counters["eyes_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_BuildRenderer(benchmark::State& state) {
  const Setup s("paper-d3");
  for (auto _ : state) benchmark::DoNotOptimize(sim::Renderer(s.rig, s.scene, sim::SensorSettings{}));
}

}  // namespace

BENCHMARK_CAPTURE(BM_RenderPair, paper_d1_mono, "paper-d1", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderPair, paper_d2_mono, "paper-d2", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderPair, paper_d3_mono, "paper-d3", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RenderPair, paper_d3_bayer, "paper-d3", true)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Irradiance)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BuildRenderer)->Unit(benchmark::kMillisecond);
int main(int argc, char** argv) {
  cv::setNumThreads(1);  // the target is one core: keep OpenCV's filters single-threaded too
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
