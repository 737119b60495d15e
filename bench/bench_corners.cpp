// Corner detection on the same rendered images in one run: ours (full search and tracked) against
// OpenCV's findChessboardCorners + cornerSubPix and findChessboardCornersSB, as a user would call
// them. Dataset: 24 stereo pairs of the paper's Dataset 3 setup (5.99 mm squares at 58-85 mm, tilts
// up to 40 degrees), every other pair Bayer, noise, blur, vignetting and defect pixels (naneye_sim).
// Each benchmark iteration detects one eye; counters: pairs found in both eyes, corner RMS and worst
// error (pixels) against the truth, each detected corner matched to its nearest true corner.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "../tests/corners/corner_test_util.hpp"
#include "naneye/recon/corners/coarse_grid.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/grid.hpp"

namespace {

using namespace naneye;

struct Eye {
  cv::Mat now, before;  // `before`: the previous frame (the board 0.1 mm / 0.3 degrees away)
  std::vector<Eigen::Vector2d> truth;
  bool bayer = false, left = true;
  int pair = 0;
};

const std::vector<Eye>& dataset() {
  static const std::vector<Eye> eyes = [] {
    std::vector<Eye> out;
    std::mt19937_64 rng(2016);
    for (int k = 0; k < 24; ++k) {
      const bool bayer = k % 2 == 1;
      const sim::Pose pose = test::random_pose(rng);
      sim::Pose prev = pose;
      prev.t += Eigen::Vector3d(0.1, -0.05, 0.1);
      prev.R = Eigen::AngleAxisd(0.005, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix() * prev.R;
      const sim::RenderedPair p = test::render(bayer, pose, 9000 + static_cast<std::uint64_t>(k));
      const sim::RenderedPair q = test::render(bayer, prev, 9500 + static_cast<std::uint64_t>(k));
      out.push_back({p.left, q.left, p.truth.left_px, bayer, true, k});
      out.push_back({p.right, q.right, p.truth.right_px, bayer, false, k});
    }
    return out;
  }();
  return eyes;
}

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// One row of the summary table printed after the runs (the figures of docs/corners.md).
struct Row {
  int pairs_found = 0, pairs = 0;
  double rms = 0, worst = 0, cpu_ms_per_eye = 0;
};
std::map<std::string, Row>& summary() {
  static std::map<std::string, Row> rows;
  return rows;
}

struct Tally {
  std::vector<bool> eye_found;
  double sum2 = 0, worst = 0;
  int n = 0;
  void add(const Eye& e, bool found, const std::vector<Eigen::Vector2d>& pts) {
    eye_found.push_back(found);
    if (!found) return;
    for (const auto& p : pts) {
      double best = 1e9;
      for (const auto& t : e.truth) best = std::min(best, (p - t).norm());
      sum2 += best * best;
      worst = std::max(worst, best);
      ++n;
    }
  }
  void report(benchmark::State& state, const std::string& name, double cpu_s) const {
    int pairs = 0;
    for (std::size_t i = 0; i + 1 < eye_found.size(); i += 2) pairs += eye_found[i] && eye_found[i + 1];
    Row& row = summary()[name];
    row.pairs_found = pairs;
    row.pairs = static_cast<int>(eye_found.size() / 2);
    row.rms = n ? std::sqrt(sum2 / n) : 0.0;
    row.worst = worst;
    row.cpu_ms_per_eye = 1e3 * cpu_s / static_cast<double>(state.iterations());
    state.counters["pairs_found"] = pairs;
    state.counters["pairs"] = static_cast<double>(eye_found.size() / 2);
    state.counters["rms_px"] = n ? std::sqrt(sum2 / n) : 0.0;
    state.counters["worst_px"] = worst;
  }
};

// What a user would feed OpenCV: 8-bit grey, demosaiced with the GRBG code (OpenCV names it by the
// second row: COLOR_BayerGB2GRAY == COLOR_BayerGRBG2GRAY).
cv::Mat to_gray8(const Eye& e) {
  cv::Mat g16, g8;
  if (e.bayer) {
    cv::cvtColor(e.now, g16, cv::COLOR_BayerGRBG2GRAY);
  } else {
    g16 = e.now;
  }
  g16.convertTo(g8, CV_8U, 0.25);
  return g8;
}

void BM_Ours(benchmark::State& state, bool tracked, bool avx2 = true) {
  const auto& eyes = dataset();
  const recon::StereoRig& rig = test::paper_d3();
  recon::CornerSettings settings;
  settings.allow_avx2 = avx2;
  recon::CornerDetector left(rig.left, settings), right(rig.right, settings);
  std::vector<recon::CornerResult> previous(eyes.size());
  for (std::size_t i = 0; i < eyes.size(); ++i) {
    (eyes[i].left ? left : right).detect_full(sim::raw_view(eyes[i].before, eyes[i].bayer), previous[i]);
  }
  recon::CornerResult res;
  std::size_t i = 0;
  int tracked_count = 0;
  Tally tally;
  double cpu = 0;
  for (auto _ : state) {
    const Eye& e = eyes[i];
    const double t0 = cpu_seconds();
    recon::CornerDetector& det = e.left ? left : right;
    const bool found = det.detect(sim::raw_view(e.now, e.bayer), tracked ? &previous[i] : nullptr, res);
    benchmark::DoNotOptimize(res);
    cpu += cpu_seconds() - t0;
    if (tally.eye_found.size() < eyes.size()) {
      std::vector<Eigen::Vector2d> pts;
      for (int k = 0; k < res.count; ++k) pts.push_back(res.corners[static_cast<std::size_t>(k)].px);
      tally.add(e, found, pts);
      tracked_count += res.tracked;
    }
    i = (i + 1) % eyes.size();
  }
  tally.report(state,
               std::string(tracked ? "ours, tracked from the previous frame" : "ours, full search") +
                   (avx2 ? "" : " (SSE2 kernels)"),
               cpu);
  if (tracked) state.counters["tracked_eyes"] = tracked_count;
}

void BM_OpenCV(benchmark::State& state, bool sb) {
  const auto& eyes = dataset();
  std::size_t i = 0;
  Tally tally;
  const cv::Size pattern(8, 6);
  double cpu = 0;
  for (auto _ : state) {
    const Eye& e = eyes[i];
    const double t0 = cpu_seconds();
    const cv::Mat g = to_gray8(e);
    std::vector<cv::Point2f> pts;
    bool found;
    if (sb) {
      found =
          cv::findChessboardCornersSB(g, pattern, pts, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY);
    } else {
      found = cv::findChessboardCorners(g, pattern, pts,
                                        cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
      if (found) {
        cv::cornerSubPix(g, pts, cv::Size(3, 3), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS | cv::TermCriteria::COUNT, 30, 0.01));
      }
    }
    benchmark::DoNotOptimize(pts);
    cpu += cpu_seconds() - t0;
    if (tally.eye_found.size() < eyes.size()) {
      std::vector<Eigen::Vector2d> p;
      for (const auto& q : pts) p.emplace_back(q.x, q.y);
      tally.add(e, found, p);
    }
    i = (i + 1) % eyes.size();
  }
  tally.report(
      state,
      sb ? "findChessboardCornersSB (NORMALIZE, ACCURACY)" : "findChessboardCorners + cornerSubPix(3x3)",
      cpu);
}

// The full search's coarse grid step alone, on the luminance the detector computes: ours (saddle
// lattice, corners/coarse_grid.hpp) against the OpenCV search the detector used before (and keeps as an
// opt-in fallback). Counter: pairs whose both eyes gave a grid.
void BM_CoarseGrid(benchmark::State& state, bool opencv) {
  const auto& eyes = dataset();
  const recon::StereoRig& rig = test::paper_d3();
  std::vector<std::vector<float>> lumas(eyes.size());
  std::vector<float> scratch(250 * 250);
  for (std::size_t i = 0; i < eyes.size(); ++i) {
    lumas[i].resize(250 * 250);
    recon::raw_to_luminance(sim::raw_view(eyes[i].now, eyes[i].bayer), lumas[i].data(), scratch.data());
  }
  recon::CoarseGridFinder left(rig.left), right(rig.right);
  std::vector<unsigned char> gray8;
  std::vector<Eigen::Vector2f> grid(recon::kMaxCorners);
  std::vector<bool> found(eyes.size());
  std::size_t i = 0;
  for (auto _ : state) {
    const recon::LumaView v{lumas[i].data(), 250, 250, 1, 249, 249};
    recon::CoarseGridFinder& finder = eyes[i].left ? left : right;
    found[i] = opencv ? recon::coarse_grid_opencv(v, 6, 8, gray8, grid) : finder.find(v, 6, 8, grid.data());
    benchmark::DoNotOptimize(grid.data());
    i = (i + 1) % eyes.size();
  }
  int pairs = 0;
  for (std::size_t k = 0; k + 1 < found.size(); k += 2) pairs += found[k] && found[k + 1];
  state.counters["pairs_found"] = pairs;
}

// What the daemon pays on every frame without a board: a full search that finds nothing (the
// luminance included). With the OpenCV fallback on, this is what every such frame cost before.
void BM_NoBoard(benchmark::State& state, bool opencv_fallback) {
  const recon::StereoRig& rig = test::paper_d3();
  std::vector<std::pair<cv::Mat, bool>> frames;
  for (int k = 0; k < 8; ++k) {
    const bool bayer = k % 2 == 1;
    frames.emplace_back(
        test::render(bayer, sim::Pose{}, 9900 + static_cast<std::uint64_t>(k), test::Scene::no_board).left,
        bayer);
  }
  recon::CornerSettings settings;
  settings.opencv_fallback = opencv_fallback;
  recon::CornerDetector det(rig.left, settings);
  recon::CornerResult res;
  std::size_t i = 0;
  int found = 0;
  for (auto _ : state) {
    found += det.detect_full(sim::raw_view(frames[i].first, frames[i].second), res);
    i = (i + 1) % frames.size();
  }
  state.counters["found"] = found;
}

// The first step of every detection: raw frame -> float luminance with the defect-pixel repair
// (mono), plus the 3x3 binomial (Bayer).
void BM_Luminance(benchmark::State& state, bool bayer) {
  const auto& eyes = dataset();
  const Eye& e = eyes[bayer ? 2 : 0];
  std::vector<float> out(250 * 250), scratch(250 * 250);
  for (auto _ : state) {
    recon::raw_to_luminance(sim::raw_view(e.now, e.bayer), out.data(), scratch.data());
    benchmark::DoNotOptimize(out.data());
  }
}

// Each run covers the 48 eyes at least once (the tallies need all of them).
BENCHMARK_CAPTURE(BM_Ours, full_search, false)->Unit(benchmark::kMillisecond)->Iterations(96);
BENCHMARK_CAPTURE(BM_Ours, tracked, true)->Unit(benchmark::kMillisecond)->Iterations(480);
BENCHMARK_CAPTURE(BM_Ours, tracked_sse2, true, false)->Unit(benchmark::kMillisecond)->Iterations(480);
BENCHMARK_CAPTURE(BM_OpenCV, findChessboardCorners_cornerSubPix, false)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(96);
BENCHMARK_CAPTURE(BM_OpenCV, findChessboardCornersSB, true)->Unit(benchmark::kMillisecond)->Iterations(96);
BENCHMARK_CAPTURE(BM_CoarseGrid, ours, false)->Unit(benchmark::kMillisecond)->Iterations(480);
BENCHMARK_CAPTURE(BM_CoarseGrid, opencv_before, true)->Unit(benchmark::kMillisecond)->Iterations(96);
BENCHMARK_CAPTURE(BM_Luminance, mono, false)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Luminance, bayer, true)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_NoBoard, ours, false)->Unit(benchmark::kMillisecond)->Iterations(400);
BENCHMARK_CAPTURE(BM_NoBoard, with_opencv_fallback, true)->Unit(benchmark::kMillisecond)->Iterations(80);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  // The table of docs/corners.md: CPU time of detect() alone (process CPU clock, not wall time: the
  // machine may be shared), per eye.
  std::printf(
      "\n| method | pairs found | corner RMS | worst corner | CPU per eye |\n|---|---|---|---|---|\n");
  for (const auto& [name, r] : summary()) {
    std::printf("| %s | %d/%d | %.4f px | %.3f px | %.2f ms |\n", name.c_str(), r.pairs_found, r.pairs, r.rms,
                r.worst, r.cpu_ms_per_eye);
  }
  return 0;
}
