// `naneye calibrate --input URI [--input URI ...] --pattern 6x8 --square-mm 5.99 -o calib.yaml`: detect the
// board in every pair, calibrate both cameras and the stereo pose in one bundle
// (naneye/recon/calibrate/calibrate.hpp), print every parameter with its sigma, and write the calibration
// YAML that everything else reads. Nothing is written when anything fails.
#include <spdlog/spdlog.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "calibrate_images.hpp"
#include "calibrate_views.hpp"
#include "cli_inputs.hpp"
#include "commands.hpp"
#include "image_pairs.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/presets.hpp"
#include "replace_file.hpp"

namespace naneye::tools {
namespace {

struct CalibrateOptions {
  std::vector<std::string> inputs;
  std::vector<std::string> left, right;  // image files or glob patterns, instead of --input
  std::string color = "mono";
  // Defaults: the paper's board, as recon::BoardGeometry states it.
  std::string pattern = pattern_text(recon::BoardGeometry{});
  double square_mm = recon::BoardGeometry{}.square_mm;
  std::string output;
  std::vector<std::string> guess;
  bool fix_k3 = false, tangential = false, cross_validate = false, json = false;
  long long max_pairs = 0;
  int max_views = 100;
  int train_views = 10;
};

// The bundle is dense (its Jacobian holds 6 columns per view), so a long recording is thinned to
// evenly spaced views: consecutive pairs of a video add little that their neighbours do not.
void thin_views(CollectedViews& v, int max_views) {
  const std::size_t n = v.views.size();
  if (max_views <= 0 || n <= static_cast<std::size_t>(max_views)) return;
  CollectedViews kept = v;
  kept.views.clear();
  kept.sources.clear();
  for (int i = 0; i < max_views; ++i) {
    const std::size_t k = static_cast<std::size_t>(i) * n / static_cast<std::size_t>(max_views);
    kept.views.push_back(v.views[k]);
    kept.sources.push_back(v.sources[k]);
  }
  spdlog::info("using {} of {} views, evenly spaced (--max-views)", max_views, n);
  v = std::move(kept);
}

// The provenance goes in as YAML comments, which load_rig (and OpenCV) skip: so YAML whatever the
// output's name says (an XML or JSON file with them appended would not load).
void write_rig(const recon::StereoRig& rig, const std::filesystem::path& out, const std::string& provenance) {
  replace_file(
      out,
      [&](const std::filesystem::path& tmp) {
        recon::save_rig(rig, tmp);
        std::ofstream f(tmp, std::ios::app);
        f << provenance;
        if (!f) throw std::runtime_error(out.string() + ": cannot be written");
      },
      ".yaml");
}

void run_calibrate(const CalibrateOptions& o) {
  const recon::BoardGeometry board = parse_board(o.pattern, o.square_mm);
  recon::CornerSettings corners;
  corners.board = board;
  if (o.inputs.empty() == o.left.empty())
    throw std::invalid_argument("give --input URI, or --left and --right image files (not both)");
  if (o.color != "mono" && o.color != "grbg") throw std::invalid_argument("--color: mono or grbg");
  const driver::ColorMode color = o.color == "grbg" ? driver::ColorMode::bayer_grbg : driver::ColorMode::mono;
  std::vector<std::filesystem::path> guess_files(o.guess.begin(), o.guess.end());
  std::vector<std::pair<std::string, std::string>> pairs;
  recon::StereoRig guess;
  if (!o.left.empty()) {
    pairs = image_pairs(o.left, o.right);
    driver::Image10 first;
    driver::read_image(pairs.front().first, driver::ImageSettings{color}, first);
    guess = guess_files.empty() ? pinhole_rig(first.width, first.height) : recon::load_rig(guess_files);
  } else {
    if (guess_files.empty()) guess_files.push_back(sim::find_calibration("paper-d3.yaml"));
    guess = recon::load_rig(guess_files);
  }

  Progress progress;
  CollectedViews views;
  recon::StereoRig lens;  // images without --guess: the first round's calibration (calibrate_images.cpp)
  if (!pairs.empty() && guess_files.empty()) {
    const CollectedViews first = collect_image_views(pairs, guess, corners, false, color, progress);
    recon::CalibrationSettings s0;
    s0.fix_k3 = o.fix_k3;
    s0.tangential = o.tangential;
    s0.image_width = guess.left.width();
    s0.image_height = guess.left.height();
    const recon::CalibrationResult r0 = recon::calibrate_stereo(first.views, board, s0);
    if (!r0.ok) throw std::runtime_error("calibration for the lens model failed: " + r0.message);
    progress.done("lens modelled from " + std::to_string(first.views.size()) + " views: " + r0.message);
    lens = r0.rig;
    views = collect_image_views(pairs, lens, corners, true, color, progress);
  } else if (!pairs.empty()) {
    views = collect_image_views(pairs, guess, corners, true, color, progress);
  } else {
    views = collect_views(o.inputs, guess, corners, o.max_pairs, progress);
  }
  if (!pairs.empty() && guess_files.empty()) guess = lens;
  if (views.views.empty())
    throw std::runtime_error("no board found in " + std::to_string(views.pairs) +
                             " pairs: check --pattern (" + o.pattern + " inner corners) and the inputs");
  thin_views(views, o.max_views);

  recon::CalibrationSettings settings;
  settings.fix_k3 = o.fix_k3;
  settings.tangential = o.tangential;
  settings.image_width = guess.left.width();
  settings.image_height = guess.left.height();
  settings.initial = &guess;
  const recon::CalibrationResult res =
      recon::calibrate_stereo(views.views, board, settings, [&](const recon::CalibrationProgress& p) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "optimising: iteration %d, RMS %.5f px", p.iteration, p.rms_px);
        progress.update(buf);
      });
  if (!res.ok) throw std::runtime_error("calibration failed: " + res.message);
  progress.done("optimised: " + res.message);

  std::unique_ptr<recon::SplitValidation> splits;
  std::unique_ptr<recon::OddEvenValidation> odd_even;
  if (o.cross_validate) {
    // Five calibrations in all: three splits, then the odd and the even half.
    progress.update(
        0.0,
        "cross-validating: " + std::to_string(3) + " splits of " + std::to_string(o.train_views) + " views",
        true);
    splits = std::make_unique<recon::SplitValidation>(
        recon::cross_validate_splits(views.views, board, settings, 3, o.train_views));
    progress.update(0.6, "cross-validating: halves of the views against each other", true);
    odd_even = std::make_unique<recon::OddEvenValidation>(
        recon::cross_validate_odd_even(views.views, board, settings));
    progress.done("cross-validation done");
  }
  std::ostringstream provenance;
  provenance << "# naneye calibrate: " << res.message << "; worst " << res.worst_px << " px, noise estimate "
             << res.sigma_px << " px per coordinate\n# pattern " << o.pattern << ", square " << o.square_mm
             << " mm, k3 " << (o.fix_k3 ? "fixed at 0" : "free") << ", tangential "
             << (o.tangential ? "free" : "fixed at 0") << "\n# *_sigma: one-sigma marginal uncertainties, "
             << "sigma^2 (J^T J)^-1 at the optimum (docs/calibration.md)\n";
  for (const auto& in : o.inputs) provenance << "# input: " << in << "\n";
  for (const auto& in : o.left) provenance << "# left: " << in << "\n";
  for (const auto& in : o.right) provenance << "# right: " << in << "\n";
  recon::StereoRig rig = res.rig;
  if (odd_even && odd_even->ok && rig.sigmas.covariance) {
    rig.sigmas.covariance_scale = odd_even->sigma_scale;
    provenance << "# cross-validation (odd against even views and two more halvings): depth ratio RMS "
               << odd_even->pooled_depth_ratio_rms << " over " << odd_even->pooled_depth_corners
               << " corners; calibration_sigma_scale " << odd_even->sigma_scale << "\n";
  }
  write_rig(rig, o.output, provenance.str());
  print_report(res, views, splits.get(), odd_even.get(), settings, {o.json, o.output});
}

}  // namespace

void add_calibrate_commands(CLI::App& app) {
  auto o = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate", "Calibrate both cameras and the stereo pose from checkerboard captures (one LM bundle)");
  cmd->add_option("--input", o->inputs,
                  "Source URI (file://, sim://...), a .raw/.neyd capture, or a folder of them; repeatable");
  cmd->add_option("--left", o->left,
                  "Left image files (PNG, JPEG, PGM, BMP, TIFF) or glob patterns, sorted by name; any size");
  cmd->add_option("--right", o->right, "Right image files or glob patterns, paired in order with --left");
  cmd->add_option("--color", o->color, "Image pixels: mono, or grbg (a raw Bayer mosaic)")
      ->capture_default_str();
  cmd->add_option("--pattern", o->pattern, "Inner corners ROWSxCOLS")->capture_default_str();
  cmd->add_option("--square-mm", o->square_mm, "Square size")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("-o,--output", o->output, "Calibration YAML to write")->required();
  cmd->add_option("--guess", o->guess,
                  "Calibration that models the lenses for corner detection and starts the optimisation "
                  "(default: the paper's Dataset 3)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--fix-k3", o->fix_k3, "Fix k3 = 0 (the paper's Datasets 1 and 2)");
  cmd->add_flag("--tangential", o->tangential, "Estimate the tangential terms p1, p2 too");
  cmd->add_flag("--cross-validate", o->cross_validate,
                "Add the paper's 3 splits (calibrate on --train-views, reconstruct the rest) and three "
                "halvings (odd/even, index mod 4); where their depths show the sigmas understate, the file "
                "gets calibration_sigma_scale");
  cmd->add_option("--train-views", o->train_views, "Views per cross-validation calibration")
      ->capture_default_str()
      ->check(CLI::Range(3, 1000));
  cmd->add_option("--max-pairs", o->max_pairs,
                  "Read at most this many pairs per input (needed for live sources)");
  cmd->add_option("--max-views", o->max_views, "Calibrate on at most this many views, evenly spaced (0: all)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--json", o->json, "Print the report as one JSON object");
  cmd->callback([o] { run_calibrate(*o); });
}

}  // namespace naneye::tools
