// How much of each scene any matcher could give depth for at the dense path's precision bound, beside
// what ours gives (issue 14: dense coverage >= 80 % of the pixels both eyes see).
//
// The bound (sim/disparity_bound.hpp): the Cramer-Rao bound of the disparity at each pixel from
// the render's noise-free twin and the sensor model's noise, at the window the matcher chose for the
// pair. The dense path refuses a pixel whose disparity sigma exceeds MatcherSettings::max_sigma_px
// (a third of the integer stage's half-pixel basin), so a pixel whose bound exceeds it is one no
// honest matcher with that rule can give: "reachable" below is the share of the pixels both eyes
// see where the bound is within it. Mono only.
//
//   build/bench/bench_scene_limits [--seeds N] [--real-sensor] [--defocus SIGMA] [--dense-radius R]
// --dense-radius R: the matcher's window fixed at R (as bench_scene's), the bound at the same window.
// --maps DIR: per render DIR/limits-SCENE-K.png (left raw grid, x2): green reachable and ours, red
// reachable and not ours, magenta ours beyond the reachable, grey neither, black not seen by both.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/disparity_bound.hpp"
#include "naneye/sim/textured.hpp"

namespace {
using namespace naneye;

// Depth bands, mm (the presets span 8-80 mm).
constexpr std::array<double, 8> kBandEdges{5, 10, 15, 20, 30, 45, 60, 150};
constexpr int kBands = static_cast<int>(kBandEdges.size()) - 1;

int band_of(double z) {
  for (int b = 0; b < kBands; ++b)
    if (z < kBandEdges[static_cast<std::size_t>(b) + 1]) return b;
  return kBands - 1;
}

// What one scene's renders give, per pixel both eyes see.
struct Counts {
  long seen = 0, reachable = 0, ours = 0, ours_reachable = 0;
  long lost_at_edge = 0;  // reachable, not ours, and the window reaches past what both eyes see
  void add(const Counts& o) {
    seen += o.seen;
    reachable += o.reachable;
    ours += o.ours;
    ours_reachable += o.ours_reachable;
    lost_at_edge += o.lost_at_edge;
  }
};

// Our depths against the bound: each one's sigma as a disparity over the bound there (a sigma below
// the bound claims more than the data hold), and its error over its sigma, inside ([0]) and outside
// ([1]) the reachable pixels.
struct Honesty {
  std::vector<double> ratio;
  double z2[2] = {};
  long bad5[2] = {}, n[2] = {};
};

struct SceneTally {
  Counts all;
  std::array<Counts, kBands> bands{};
  Honesty honesty;
  std::string radii;
};

double pct(long a, long b) {
  return b > 0 ? 100.0 * double(a) / double(b) : NAN;
}

// One pair: our depth map against the bound at the matcher's window r. `map` (optional, CV_8UC3):
// green reachable and ours, red reachable and lost, magenta ours beyond the reachable, grey neither.
void tally_pair(const cv::Mat& truth, const recon::scene::DepthMap& depth, const cv::Mat& bound, int r,
                double max_sigma, const recon::StereoRig& rig, SceneTally& t, cv::Mat* map) {
  cv::Mat seen = cv::Mat::zeros(truth.size(), CV_8UC1);
  for (int v = 0; v < truth.rows; ++v)
    for (int u = 0; u < truth.cols; ++u) seen.at<std::uint8_t>(v, u) = std::isfinite(truth.at<double>(v, u));
  cv::Mat inner;  // a full (2 r + 1)^2 window of seen pixels
  cv::erode(seen, inner, cv::Mat::ones(2 * r + 1, 2 * r + 1, CV_8UC1), cv::Point(-1, -1), 1,
            cv::BORDER_CONSTANT, cv::Scalar(0));
  if (map) map->create(truth.size(), CV_8UC3), map->setTo(cv::Scalar(0, 0, 0));
  for (int v = 0; v < truth.rows; ++v)
    for (int u = 0; u < truth.cols; ++u) {
      const double zt = truth.at<double>(v, u);
      if (!std::isfinite(zt)) continue;
      Counts one;
      one.seen = 1;
      one.reachable = bound.at<double>(v, u) <= max_sigma;
      one.ours = std::isfinite(depth.z_at(u, v));
      one.ours_reachable = one.ours && one.reachable;
      one.lost_at_edge = one.reachable && !one.ours && !inner.at<std::uint8_t>(v, u);
      t.all.add(one);
      t.bands[static_cast<std::size_t>(band_of(zt))].add(one);
      if (map) {
        static const cv::Vec3b kColour[2][2] = {{{90, 90, 90}, {255, 0, 255}}, {{0, 0, 255}, {0, 160, 0}}};
        map->at<cv::Vec3b>(v, u) = kColour[one.reachable][one.ours];
      }
      if (!one.ours) continue;
      const double z = depth.z_at(u, v), sz = depth.sigma_at(u, v);
      const double sd = sim::disparity_sigma(rig, Eigen::Vector2d(u, v), z, sz);
      Honesty& h = t.honesty;
      // No bound where the window had too little seen data for one (counted as not reachable).
      if (std::isfinite(bound.at<double>(v, u))) h.ratio.push_back(sd / bound.at<double>(v, u));
      const int out = one.reachable ? 0 : 1;
      h.z2[out] += (z - zt) * (z - zt) / (sz * sz);
      h.bad5[out] += std::abs(z - zt) > 0.05 * zt;
      ++h.n[out];
    }
}

void print_coverage_header() {
  std::printf("%-10s | %7s %8s %8s %9s %8s %9s | %s\n", "scene", "seen", "reach %", "ours %", "ours/re %",
              "edge %", "ours!re %", "reach % / ours % by depth band (mm)");
  std::printf("%-10s | %56s |", "", "");
  for (int b = 0; b < kBands; ++b)
    std::printf(" %5.0f-%-5.0f", kBandEdges[static_cast<std::size_t>(b)],
                kBandEdges[static_cast<std::size_t>(b) + 1]);
  std::printf("\n");
}

void print_coverage(const std::string& name, const SceneTally& t, int seeds) {
  const Counts& a = t.all;
  std::printf("%-10s | %7ld %7.1f%% %7.1f%% %8.1f%% %7.1f%% %8.1f%% |", name.c_str(), a.seen / seeds,
              pct(a.reachable, a.seen), pct(a.ours, a.seen), pct(a.ours_reachable, a.reachable),
              pct(a.lost_at_edge, a.reachable - a.ours_reachable), pct(a.ours - a.ours_reachable, a.ours));
  for (const Counts& b : t.bands) {
    if (b.seen * 200 < a.seen)  // under 0.5 % of the scene: no figure
      std::printf(" %11s", "-");
    else
      std::printf(" %5.1f/%-5.1f", pct(b.reachable, b.seen), pct(b.ours, b.seen));
  }
  std::printf(" | r %s\n", t.radii.c_str());
}

void print_honesty(const std::vector<std::pair<std::string, SceneTally>>& rows, int seeds) {
  std::printf("\n%-10s | %-29s | %-21s | %-29s\n", "", "our sigma / bound", "reachable",
              "outside the reachable");
  std::printf("%-10s | %9s %9s %9s | %10s %10s | %10s %10s %7s\n", "scene", "p5", "p50", "< 1 %", "rms(e/s)",
              "bad-5 %", "rms(e/s)", "bad-5 %", "pix");
  for (const auto& [name, t] : rows) {
    std::vector<double> ratio = t.honesty.ratio;
    std::sort(ratio.begin(), ratio.end());
    const auto q = [&](double f) {
      return ratio.empty() ? NAN : ratio[static_cast<std::size_t>(f * double(ratio.size() - 1))];
    };
    const long below = std::lower_bound(ratio.begin(), ratio.end(), 1.0) - ratio.begin();
    const Honesty& h = t.honesty;
    std::printf("%-10s | %9.2f %9.2f %8.2f%% | %10.2f %9.2f%% | %10.2f %9.2f%% %7ld\n", name.c_str(), q(0.05),
                q(0.5), pct(below, static_cast<long>(ratio.size())),
                std::sqrt(h.z2[0] / std::max(1L, h.n[0])), pct(h.bad5[0], h.n[0]),
                std::sqrt(h.z2[1] / std::max(1L, h.n[1])), pct(h.bad5[1], h.n[1]), h.n[1] / seeds);
  }
  std::printf(
      "our sigma / bound: each of our depths' sigma (as a disparity) over the Cramer-Rao bound at its pixel "
      "(no estimator is below 1; the sigma is itself an estimate, so some are); rms(e/s): of "
      "(Z - Z_true) / sigma; pix: our depths outside the reachable per pair\n");
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 2;
  sim::SensorSettings sensor;
  recon::scene::DenseSettings ds;
  std::string maps;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--real-sensor")) sensor = sim::SensorSettings::measured(false);
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) seeds = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--defocus") && i + 1 < argc) sensor.defocus_sigma_px = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--dense-radius") && i + 1 < argc)
      ds.matcher.radius = ds.matcher.max_radius = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--maps") && i + 1 < argc) maps = argv[++i];
  }
  if (seeds < 1) {
    std::fprintf(stderr, "bench_scene_limits: --seeds must be >= 1\n");
    return 2;
  }
  if (!maps.empty()) std::filesystem::create_directories(maps);
  const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  const sim::TexturedRenderer renderer(rig, sensor), clean_renderer(rig, sim::noise_free_twin(sensor));
  recon::scene::SparseReconstructor sparse(rig);  // its luminance feeds the dense path, as in the daemon
  recon::scene::SparseResult points;
  recon::scene::DenseReconstructor dense(rig, ds);
  recon::scene::DepthMap depth;
  const double max_sigma = dense.settings().matcher.max_sigma_px;
  std::printf("bench_scene_limits: %d renders per scene, mono, blur sigma %.2f px, %s; sigma bound %.3f px\n",
              seeds, sensor.blur_sigma_px(),
              sensor.dsnu_dn > 0 ? "the real sensor's noise and fixed patterns" : "the simulator's sensor",
              max_sigma);
  print_coverage_header();
  std::vector<std::pair<std::string, SceneTally>> rows;
  for (const auto& name : sim::textured_preset_names()) {
    SceneTally t;
    for (int k = 0; k < seeds; ++k) {
      // The same renders as bench_scene's; the noise-free twin through the same rule.
      const sim::TexturedPair p = sim::numbered_render(renderer, name, k);
      const sim::TexturedPair c = sim::numbered_render(clean_renderer, name, k);
      sparse.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), points);
      dense.reconstruct(sparse.luma(), depth);
      const int r = dense.matcher().radius_used();
      t.radii += (t.radii.empty() ? "" : " ") + std::to_string(r);
      const cv::Mat bound = sim::disparity_bound(rig, sensor, c.left, p.depth, r);
      cv::Mat map;
      tally_pair(p.depth, depth, bound, r, max_sigma, rig, t, maps.empty() ? nullptr : &map);
      if (!maps.empty()) {
        cv::resize(map, map, cv::Size(), 2, 2, cv::INTER_NEAREST);
        const auto file = std::filesystem::path(maps) / ("limits-" + name + "-" + std::to_string(k) + ".png");
        if (!cv::imwrite(file.string(), map))
          std::fprintf(stderr, "bench_scene_limits: cannot write %s\n", file.c_str());
      }
    }
    print_coverage(name, t, seeds);
    rows.emplace_back(name, std::move(t));
  }
  std::printf(
      "seen: pixels both eyes see per pair; reach: of them, where the Cramer-Rao bound of the disparity is "
      "within the dense path's sigma bound; ours: our dense coverage; ours/re: of the reachable pixels, "
      "the share we give; edge: of the reachable we do not give, the share whose window reaches past what "
      "both eyes see; ours!re: of ours, the share outside the reachable; r: our window per pair\n");
  print_honesty(rows, seeds);
  return 0;
}
