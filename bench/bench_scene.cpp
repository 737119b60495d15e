// Sparse scene reconstruction, ours vs the OpenCV path a user would glue together (issue 14), on the
// same textured renders in one run, against their exact truth:
//   ours:   recon::scene::SparseReconstructor (docs/scene.md)
//   OpenCV: goodFeaturesToTrack + calcOpticalFlowPyrLK left -> right (from zero disparity) +
//           undistortPoints + triangulatePoints (P1 = [I|0], P2 = [R|T]), on the same luminance
//           (raw_to_luminance, its 10-bit scale to 8 bits for OpenCV, the same for both eyes).
// An outlier is a point whose left pixel sees no surface the right eye sees, or whose depth is off
// by more than 5 %. CPU time of this thread per pair, OpenCV limited to one thread.
//   build/bench/bench_scene [--seeds N] [--repeat N] [--bayer] [--real-sensor] [--defocus SIGMA]
//       [--refusals] [--digest] [--residual-p P] [--max-sigma PX] [--min-zncc Z] [--min-final-zncc Z]
//       [--raw-search] [--max-shift-sigma PX] [--max-points N] [--wide-radius R] [--wide-step S]
//       [--dense-radius R] [--max-radius R] [--dense-iterations N] [--gain E_PER_DN] [--read-noise DN]
//       [--no-vignetting]
//       [--supersample N] [--sparse-only] [--curvature-radius PX] [--wide-false-reject P] [--nested-only]
// --refusals: the dense path's MatchCounts per scene (each rectified pixel counted at the first
// validity test it fails), summed over the renders, in % of the candidates; and the sparse path's
// features per pair by status. What-ifs, one setting changed: --residual-p P, --max-sigma PX, the
// dense validity tests' (dense_match.hpp); --min-zncc Z, --min-final-zncc Z, the sparse coarse
// search's and LK match's acceptance (sparse.hpp); --raw-search, that search on the unfiltered mono
// luminance (SparseSettings::search_binomial off); --max-shift-sigma PX, the feature gate's
// Cramer-Rao shift bound (FeatureSettings, features.hpp); --max-points N, the valid points where
// matching stops (SparseSettings::max_points: fewer points in less time; the covering lattice is
// tried first whatever N, so they are not the strongest); --wide-radius R, the sparse path's wider
// LK window (0: the narrow window only); --wide-step S, its nested widening's ring, px (sparse.hpp);
// --curvature-radius PX, the curvature model's neighbourhood (0: off); --wide-false-reject P, the
// widening's tests' false-reject rate; --nested-only, the ladder for every feature, without the one
// step to the widest window first (SparseSettings::wide_direct off). --sparse-only: the sparse paths
// alone (~15 s, not ~2 min). The sparse table's last columns: rms(err / depth_sigma_mm) over our good points,
// the sigma's honesty (0.7-1.4 is the band), and our mean error over the OpenCV path's (the issue's
// target: <= 0.5). --dense-radius R: the dense sub-pixel window, fixed;
// --max-radius R: the largest window the matcher may choose per pair (R = 3: fixed at 3, as before
// the choice). --dense-iterations N: the dense sub-pixel step's Gauss-Newton passes (default 4). The dense
// table's r column: the radius each pair was matched with, in render order (the matcher carries it from pair
// to pair, and from scene to scene: one matcher for the run, as in the daemon).
// --defocus SIGMA: the renders' defocus blur, px (sim/sensor.hpp; default 0.35, with diffraction
// 0.41 px in all: ~3x sharper than a real NanEye's edges, 1.0-1.6 px, ../shared/notes/measurements.md).
// The error budget's sensor terms, one at a time: --gain E_PER_DN (shot noise; 1e6: none) and
// --read-noise DN (sim/sensor.hpp), --no-vignetting, --supersample N (the renderer's sub-samples per
// pixel side, default 3), beside --no-noise, --no-fixed-pattern and --no-offsets below.
// --repeat N: each path reconstructs every render N times, all timed (steadier medians; a profile
// of the paths rather than of the renderer under perf). The sparse ids then follow the repeats.
// --digest: per scene, one 64-bit FNV-1a hash over every render's sparse points (status, id, both
// pixels, xyz, sigma) and one over its dense maps (depth and sigma), to show a speed change leaves
// the results bit for bit as they were (run before and after with the same flags, compare the lines).
// --real-sensor: the renders through the real NanEye's measured figures (sim::SensorSettings::measured:
// blur 1.0 px, its shot and read noise, fixed-pattern noise, the reset line); --defocus still applies.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/flat_field.hpp"
#include "naneye/sim/textured.hpp"
#include "scene_opencv.hpp"
#include "scene_tally.hpp"
#include "thread_clock.hpp"

using namespace naneye;
using namespace naneye::bench_scene;
using naneye::bench::thread_cpu_s;

void add_counts(recon::scene::MatchCounts& s, const recon::scene::MatchCounts& c) {
  s.candidates += c.candidates;
  s.no_integer += c.no_integer;
  s.window += c.window;
  s.shift += c.shift;
  s.texture += c.texture;
  s.converged += c.converged;
  s.residual += c.residual;
  s.left_right += c.left_right;
  s.band_edge += c.band_edge;
  s.occluded += c.occluded;
  s.valid += c.valid;
}

// Where the rectified candidates go: the first validity test each one fails (docs/scene.md, Validity).
void print_refusals(const std::vector<recon::scene::MatchCounts>& rows) {
  std::printf("\n%-10s | %8s %7s %7s %7s %7s %7s %7s %7s %7s %7s %7s\n", "refusals", "cand", "no-int", "l-r",
              "band", "window", "shift", "sigma", "conv", "chi2", "occl", "valid");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto& c = rows[k];
    const double n = std::max(1, c.candidates) / 100.0;
    std::printf(
        "%-10s | %8d %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%% %6.1f%%\n",
        sim::textured_preset_names()[k].c_str(), c.candidates, c.no_integer / n, c.left_right / n,
        c.band_edge / n, c.window / n, c.shift / n, c.texture / n, c.converged / n, c.residual / n,
        c.occluded / n, c.valid / n);
  }
  std::printf("%% of the rectified candidates (left data), summed over the renders\n");
}

// The sparse path's features per pair by their status (sparse.hpp PointStatus), per scene.
constexpr int kStatuses = static_cast<int>(recon::scene::PointStatus::imprecise) + 1;
using StatusRow = std::array<long, kStatuses>;
// Per LK window radius (ScenePoint::window_radius_px): good points, and their sums of dZ / sigma (its
// mean shows a bias the rms hides: a curved surface's, of its sign) and of its square.
struct WindowTally {
  long points = 0;
  double z = 0, z2 = 0;  // sums of dZ / sigma (signed: a bias shows) and of its square
};
using WidenedRow = std::array<WindowTally, recon::scene::kMaxLkRadius + 1>;

void print_sparse_refusals(const std::vector<StatusRow>& rows, const std::vector<WidenedRow>& widened,
                           const recon::scene::SparseSettings& ss, const std::vector<int>& wide_radii,
                           int seeds) {
  std::printf("\n%-10s |", "features");
  for (int k = 0; k < kStatuses; ++k)
    std::printf(" %9.9s", recon::scene::to_string(static_cast<recon::scene::PointStatus>(k)));
  std::printf("\n");
  for (std::size_t r = 0; r < rows.size(); ++r) {
    std::printf("%-10s |", sim::textured_preset_names()[r].c_str());
    for (long n : rows[r]) std::printf(" %9.1f", double(n) / seeds);
    std::printf("\n");
  }
  std::printf("sparse features tried per pair, by status (matching stops at max_points valid)\n");
  std::vector<int> radii{ss.lk.radius};
  radii.insert(radii.end(), wide_radii.begin(), wide_radii.end());
  std::printf("\n%-10s |", "window");
  for (int r : radii) std::printf(" %7dx%-12d", 2 * r + 1, 2 * r + 1);
  std::printf("\n");
  for (std::size_t k = 0; k < widened.size(); ++k) {
    std::printf("%-10s |", sim::textured_preset_names()[k].c_str());
    for (int r : radii) {
      const WindowTally& w = widened[k][static_cast<std::size_t>(r)];
      const double m = static_cast<double>(std::max(1L, w.points));
      std::printf(" %6.1f %6.2f %+6.2f", double(w.points) / seeds, std::sqrt(w.z2 / m), w.z / m);
    }
    std::printf("\n");
  }
  std::printf(
      "good sparse points per pair by the LK window their match came from (side, px), their rms(e/s) and "
      "mean(e/s)\n");
}

int main(int argc, char** argv) {
  int seeds = 3;
  int repeat = 1;  // reconstructions timed per render: > 1 for perf and steadier times
  bool bayer = false, refusals = false, digest = false, sparse_only = false;
  int pattern_frames = 0;
  int supersample = 3;  // the renderer's default (sim/textured.hpp)
  recon::scene::DenseSettings ds;
  recon::scene::SparseSettings ss;
  sim::SensorSettings sensor;
  for (int i = 1; i < argc; ++i)
    if (!std::strcmp(argv[i], "--real-sensor")) sensor = sim::SensorSettings::measured(false);
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) seeds = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
    if (!std::strcmp(argv[i], "--bayer")) bayer = true;
    if (!std::strcmp(argv[i], "--refusals")) refusals = true;
    if (!std::strcmp(argv[i], "--digest")) digest = true;
    // The sparse paths alone (ours and OpenCV's), for a quicker turn on a sparse question.
    if (!std::strcmp(argv[i], "--sparse-only")) sparse_only = true;
    // What-if: one validity test loosened, to see what the pixels it refuses would give.
    if (!std::strcmp(argv[i], "--residual-p") && i + 1 < argc) ds.matcher.residual_p = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--max-sigma") && i + 1 < argc) ds.matcher.max_sigma_px = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--min-zncc") && i + 1 < argc) ss.min_zncc = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--raw-search")) ss.search_binomial = false;
    if (!std::strcmp(argv[i], "--max-shift-sigma") && i + 1 < argc)
      ss.features.max_shift_sigma_px = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--min-final-zncc") && i + 1 < argc) ss.min_final_zncc = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--max-points") && i + 1 < argc) ss.max_points = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--wide-radius") && i + 1 < argc) ss.wide_radius = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--wide-step") && i + 1 < argc) ss.wide_step = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--nested-only")) ss.wide_direct = false;
    if (!std::strcmp(argv[i], "--wide-false-reject") && i + 1 < argc)
      ss.wide_false_reject = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--curvature-radius") && i + 1 < argc)
      ss.curvature_radius_px = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--dense-radius") && i + 1 < argc)
      ds.matcher.radius = ds.matcher.max_radius = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--max-radius") && i + 1 < argc) ds.matcher.max_radius = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--band-from-sparse")) ds.band_from_sparse = true;
    if (!std::strcmp(argv[i], "--band-margin") && i + 1 < argc) ds.band_margin_px = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--dense-iterations") && i + 1 < argc)
      ds.matcher.iterations = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--defocus") && i + 1 < argc) sensor.defocus_sigma_px = std::atof(argv[++i]);
    // The error budget: one term of the sensor off, to see what it costs.
    if (!std::strcmp(argv[i], "--no-fixed-pattern")) {
      sensor.column_fpn_dn = sensor.dsnu_dn = sensor.prnu = 0.0;
      sensor.reset_rows = 0;
    }
    if (!std::strcmp(argv[i], "--no-noise")) sensor.noise = false;
    if (!std::strcmp(argv[i], "--no-vignetting")) sensor.vignetting = false;
    if (!std::strcmp(argv[i], "--gain") && i + 1 < argc) sensor.gain_e_per_dn = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--read-noise") && i + 1 < argc) sensor.read_noise_dn = std::atof(argv[++i]);
    if (!std::strcmp(argv[i], "--supersample") && i + 1 < argc) supersample = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--no-offsets")) sensor.column_fpn_dn = sensor.dsnu_dn = 0.0;
    // The fixed pattern measured from N dark and N flat frames and removed from every render before
    // both paths (docs/sensor-calibration.md): what a user who calibrated the sensor gets.
    if (!std::strcmp(argv[i], "--fixed-pattern") && i + 1 < argc) pattern_frames = std::atoi(argv[++i]);
  }
  cv::setNumThreads(1);  // one core for both paths
  const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  sensor.bayer = bayer;
  const sim::TexturedRenderer renderer(rig, sensor, supersample);
  // A flat at 0.7 of white: ~530 DN of signal at the centre, ~320 at the corners.
  const recon::StereoFixedPattern pattern =
      pattern_frames > 0 ? sim::measure_fixed_pattern(sensor, pattern_frames, 0.7, 0xF1A7)
                         : recon::StereoFixedPattern{};
  std::vector<std::uint16_t> fixed_left, fixed_right;
  recon::scene::SparseResult res;
  recon::scene::DepthMap depth;
  OpenCvDense cv_dense(rig);
  std::vector<std::pair<DenseTally, DenseTally>> dense_rows;
  std::vector<CommonTally> common_rows;
  std::vector<recon::scene::MatchCounts> refused;
  std::vector<StatusRow> statuses;
  std::vector<WidenedRow> widened;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> digests;
  std::printf("bench_scene: %d renders per scene, %s, blur sigma %.2f px, %s, paper-d3 rig, one thread\n",
              seeds, bayer ? "GRBG Bayer" : "mono", sensor.blur_sigma_px(),
              sensor.dsnu_dn > 0 ? "the real sensor's noise and fixed patterns" : "the simulator's sensor");
  if (!pattern.left.empty())
    std::printf(
        "fixed pattern removed: %d dark + %d flat frames per eye; left DSNU %.2f DN (map se %.2f), PRNU "
        "%.2f %% (map se %.2f %%)\n",
        pattern.left.dark_frames, pattern.left.flat_frames, pattern.left.dsnu_dn, pattern.left.dark_se_dn,
        100 * pattern.left.prnu, 100 * pattern.left.gain_se);
  std::printf("%-10s | %-44s | %-44s\n", "", "ours (sparse)", "OpenCV path");
  std::printf("%-10s | %7s %7s %9s %9s %7s | %7s %7s %9s %9s %7s | %s\n", "scene", "p50 ms", "pts", "good",
              "outl %", "err %", "p50 ms", "pts", "good", "outl %", "err %",
              "ours rms(e/s) | err / OpenCV's");
  for (const auto& name : sim::textured_preset_names()) {
    // Each scene starts with fresh reconstructors, as a camera switched on in front of it would: the
    // dense window radius and the sparse ids carry over between pairs, and carried from one preset
    // to the next they made a scene's figures depend on the one before it (the height field after
    // the tube inherited the tube's r = 4; the Bayer tube lost a radius trial and waited 16 pairs).
    recon::scene::SparseReconstructor ours(rig, ss);
    recon::scene::DenseReconstructor dense(rig, ds);
    Tally a, b;
    DenseTally da, db;
    CommonTally both;
    recon::scene::MatchCounts mc;
    StatusRow st{};
    WidenedRow wd{};
    Digest dg_sparse, dg_dense;
    for (int s = 0; s < seeds; ++s) {
      const sim::TexturedPair p = sim::numbered_render(renderer, name, s);
      auto lv = sim::raw_view(p.left, bayer), rv = sim::raw_view(p.right, bayer);
      sim::remove_fixed_pattern(pattern, lv, rv, fixed_left, fixed_right);
      for (int k = 0; k < repeat; ++k) {
        const double t0 = thread_cpu_s();
        ours.reconstruct(lv, rv, res);
        a.ms.push_back(1e3 * (thread_cpu_s() - t0));
      }
      ++a.pairs;
      digest_sparse(dg_sparse, res);
      for (const auto& q : res.points) {
        ++st[static_cast<std::size_t>(q.status)];
        if (!q.valid()) continue;
        const double e = a.add(q.X.z(), p.depth, q.left_px.x(), q.left_px.y(), q.depth_sigma_mm);
        if (std::isfinite(e)) {  // a good point
          WindowTally& w = wd[static_cast<std::size_t>(q.window_radius_px)];
          ++w.points;
          w.z += e;
          w.z2 += e * e;
        }
      }
      opencv_path(rig, ours.luma(), p.depth, b);
      if (sparse_only) continue;
      // Dense on the luminance the sparse path made (the daemon shares it the same way).
      for (int k = 0; k < repeat; ++k) {
        const double t1 = thread_cpu_s();
        dense.reconstruct(ours.luma(), depth, &res);
        da.ms.push_back(1e3 * (thread_cpu_s() - t1));
      }
      dg_dense.add(depth.z_mm.data(), depth.z_mm.size() * sizeof(float));
      dg_dense.add(depth.sigma_mm.data(), depth.sigma_mm.size() * sizeof(float));
      da.add(cv::Mat(depth.height, depth.width, CV_32FC1, depth.z_mm.data()), p.depth);
      add_counts(mc, dense.match_counts());
      da.radii += (da.radii.empty() ? "" : " ") + std::to_string(dense.matcher().radius_used());
      da.bands += (da.bands.empty() ? "" : " ") + std::to_string(dense.matcher().band_min()) + "+" +
                  std::to_string(dense.matcher().band_size());
      cv_dense.run(ours.luma(), p.depth, db);
      both.add(cv::Mat(depth.height, depth.width, CV_32FC1, depth.z_mm.data()), cv_dense.z, p.depth);
    }
    dense_rows.emplace_back(da, db);
    common_rows.push_back(both);
    refused.push_back(mc);
    statuses.push_back(st);
    widened.push_back(wd);
    digests.emplace_back(dg_sparse.h, dg_dense.h);
    auto row = [](Tally& t) {
      std::printf(" %7.2f %7.0f %9.0f %8.2f%% %6.2f%%", t.p50(), double(t.points) / t.pairs,
                  double(t.points - t.outliers) / t.pairs, 100.0 * t.outliers / std::max(1L, t.points),
                  100.0 * t.rel_err_sum / std::max(1L, t.inliers));
    };
    std::printf("%-10s |", name.c_str());
    row(a);
    std::printf(" |");
    row(b);
    // The target is this ratio (<= 0.5): from the unrounded errors.
    const auto mean_err = [](const Tally& t) { return t.rel_err_sum / std::max(1L, t.inliers); };
    std::printf(" | %6.2f        | %5.3fx\n", std::sqrt(a.z2_sum / std::max(1L, a.z_count)),
                mean_err(a) / mean_err(b));
  }
  std::printf(
      "pts/good: points per pair, all and within 5 %% of the truth where both eyes see it; outl: the "
      "rest; err: mean |dZ|/Z of the good ones\n\n");
  for (std::size_t k = 0; sparse_only && k < dense_rows.size(); ++k) dense_rows[k] = {};
  if (!sparse_only) {
    std::printf("%-10s | %-50s | %-50s\n", "", "ours (dense)", "OpenCV dense path");
    std::printf("%-10s | %7s %7s %8s %8s %8s %8s | %7s %7s %8s %8s %8s %8s\n", "scene", "p50 ms", "pix",
                "cover %", "unseen %", "err %", "bad-5 %", "p50 ms", "pix", "cover %", "unseen %", "err %",
                "bad-5 %");
    for (std::size_t k = 0; k < dense_rows.size(); ++k) {
      auto row = [&](DenseTally& t) {
        std::printf(" %7.2f %7.0f %7.1f%% %7.2f%% %7.2f%% %7.2f%%", t.p50(), double(t.valid) / seeds,
                    100.0 * t.covered / std::max(1L, t.truth), 100.0 * t.unseen / std::max(1L, t.valid),
                    100.0 * t.rel_sum / std::max(1L, t.covered), 100.0 * t.bad5 / std::max(1L, t.covered));
      };
      std::printf("%-10s |", sim::textured_preset_names()[k].c_str());
      row(dense_rows[k].first);
      std::printf(" |");
      row(dense_rows[k].second);
      std::printf(" | r %s | band %s\n", dense_rows[k].first.radii.c_str(),
                  dense_rows[k].first.bands.c_str());
    }
    std::printf(
        "pix: pixels with depth per pair; cover: of the pixels where both eyes see the surface; unseen: "
        "depths where the truth has none, of all given; err: mean |dZ|/Z; bad-5: |dZ|/Z > 5 %%; r: our "
        "window "
        "radius per pair, px; band: the SGM's disparities per pair, first + count (px)\n");
    std::printf("\n%-10s | %9s | %-17s | %-17s\n", "same pixels", "", "ours (dense)", "OpenCV dense path");
    std::printf("%-10s | %9s | %8s %8s | %8s %8s\n", "scene", "pix", "err %", "bad-5 %", "err %", "bad-5 %");
    for (std::size_t k = 0; k < common_rows.size(); ++k) {
      const CommonTally& c = common_rows[k];
      const double n = static_cast<double>(std::max(1L, c.pix));
      std::printf("%-10s | %9.0f | %7.2f%% %7.2f%% | %7.2f%% %7.2f%%\n",
                  sim::textured_preset_names()[k].c_str(), c.pix / static_cast<double>(seeds),
                  100 * c.rel_ours / n, 100 * c.bad_ours / n, 100 * c.rel_cv / n, 100 * c.bad_cv / n);
    }
    std::printf("the pixels both dense paths give a depth where the truth has one, per pair\n");
  }
  if (digest)
    for (std::size_t k = 0; k < digests.size(); ++k)
      std::printf("digest %-10s sparse %016llx dense %016llx\n", sim::textured_preset_names()[k].c_str(),
                  static_cast<unsigned long long>(digests[k].first),
                  static_cast<unsigned long long>(digests[k].second));
  if (refusals) {
    print_refusals(refused);
    const recon::scene::SparseReconstructor sparse(rig, ss);  // for its window radii
    print_sparse_refusals(statuses, widened, ss, sparse.wide_radii(), seeds);
  }
  return 0;
}
