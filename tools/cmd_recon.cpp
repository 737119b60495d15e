// `naneye recon --calib FILE --input URI [--json]`: one result per stereo pair, in stream order, pairs
// without a board included. A file is replayed at max speed with a lossless hand-over: no pair is
// ever dropped. The per-pair step and the JSON are naneyed's too (naneye_app: one code path, one
// serializer).
// `--left L... --right R...` reads image pairs instead (any size, that of the calibration; the
// images:// reader, driver::read_image): a pair that cannot be read is reported and skipped.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_inputs.hpp"
#include "commands.hpp"
#include "image_pairs.hpp"
#include "naneye/app/depth_png.hpp"
#include "naneye/app/fixed_pattern_step.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/app/result_json.hpp"
#include "naneye/app/scene_json.hpp"
#include "naneye/app/sources.hpp"
#include "naneye/driver/image_file.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "source_pairs.hpp"

namespace naneye::tools {
namespace {

struct ReconOptions {
  std::vector<std::string> calib;
  std::string input;
  std::vector<std::string> left, right;  // image files (or glob patterns), instead of --input
  std::string color = "mono";
  bool json = false;
  // Defaults: recon's (the paper's board, the reconstruction's corner sigma), as naneyed's.
  std::string pattern = pattern_text(recon::BoardGeometry{});
  double square_mm = recon::BoardGeometry{}.square_mm;
  double corner_sigma_px = recon::ReconstructionSettings{}.corner_sigma_px;
  bool no_tracking = false;
  long long max_pairs = -1;
  bool scene = false;
  std::string depth_out;
  std::string fixed_pattern;  // the sensor's, removed from both frames first (as naneyed's [sensor])
};

// DIR/depth-NNNNNN.png and DIR/sigma-NNNNNN.png (issue 14; app/depth_png.hpp's format: 16-bit,
// 0.01 mm per unit on the left raw grid, 0 = none). With a calibration that carries its covariance
// also DIR/calib-sigma-NNNNNN.png: the depth sigma the calibration allows (systematic, common to the
// map; DepthMap::calib_sigma_mm).
void write_depth_pngs(const std::filesystem::path& dir, unsigned long long pair,
                      const recon::scene::DepthMap& m, bool calib_sigma, cv::Mat& u16) {
  const auto write = [&](app::DepthLayer layer, const char* file) {
    app::encode_depth_layer(app::layer_values(m, layer), m.width, m.height, layer, u16);
    char name[64];
    std::snprintf(name, sizeof name, "%s-%06llu.png", file, pair);
    if (!cv::imwrite((dir / name).string(), u16))
      throw std::runtime_error("cannot write " + (dir / name).string());
  };
  write(app::DepthLayer::depth, "depth");
  write(app::DepthLayer::sigma, "sigma");
  if (calib_sigma) write(app::DepthLayer::calib_sigma, "calib-sigma");
}

void print_scene_line(const recon::scene::SparseResult& s, const recon::scene::DepthMap* d) {
  double sigma = 0;
  for (const auto& p : s.points)
    if (p.valid()) sigma += p.depth_sigma_mm;
  std::printf("        scene: %d/%zu points valid, mean depth sigma %.3f mm\n", s.valid_count,
              s.points.size(), s.valid_count ? sigma / s.valid_count : NAN);
  if (d)
    std::printf("        dense: %d/%d visible pixels with depth (%.1f %%), median %.2f mm\n", d->valid_count,
                d->visible_count, 100 * d->valid_share, d->median_mm);
}

// "no_board_left (left: low_contrast, right: none)": what a user reads to tell "too dark" from
// "no board" (the detector's reasons: recon::CornerFailure).
std::string failure_text(const recon::PairResult& r) {
  if (!r.failure) return "unknown";
  std::string s = r.failure;
  if (r.failure_left && r.failure_right)
    s += std::string(" (left: ") + r.failure_left + ", right: " + r.failure_right + ")";
  return s;
}

void print_line(const recon::PairResult& r) {
  if (!r.board_found) {
    std::printf("pair %llu  no board: %s\n", static_cast<unsigned long long>(r.pair),
                failure_text(r).c_str());
    return;
  }
  int valid = 0;
  double sigma = 0;
  for (int i = 0; i < r.point_count; ++i) {
    valid += r.points[i].valid;
    if (r.points[i].valid) sigma += r.points[i].depth_sigma_mm;
  }
  std::printf("pair %llu  board at %.3f mm (pose rms %.4f px)  %d/%d points, mean depth sigma %.3f mm",
              static_cast<unsigned long long>(r.pair), r.board->distance_mm, r.board->rms_px, valid,
              r.point_count, valid ? sigma / valid : NAN);
  if (r.metrics)
    std::printf("  P %.4f mm  D %.4f mm  R %.4f px", r.metrics->planarity_mm, r.metrics->distance_error_mm,
                r.metrics->reprojection_px);
  std::printf("\n");
}

// Prints each result as it comes (text or JSON lines) and the summary at the end.
class Report {
 public:
  explicit Report(bool json) : json_(json) {}
  void pair(const recon::PairResult& r, const recon::scene::SparseResult* scene,
            const recon::scene::DepthMap* depth) {
    ++pairs_;
    found_ += r.board_found;
    if (!r.board_found) {
      ++outcomes_[r.failure ? r.failure : "unknown"];
      if (r.failure_left) ++left_reasons_[r.failure_left];
      if (r.failure_right) ++right_reasons_[r.failure_right];
    }
    if (json_) {
      nlohmann::json j = app::result_to_json(r);
      if (!r.board_found) {
        j["failure"] = {{"outcome", r.failure ? r.failure : "unknown"},
                        {"left", r.failure_left ? r.failure_left : "unknown"},
                        {"right", r.failure_right ? r.failure_right : "unknown"}};
      }
      if (scene) j["scene"] = app::scene_to_json(*scene, depth);
      std::cout << j.dump() << "\n";
    } else {
      print_line(r);
      if (scene) print_scene_line(*scene, depth);
    }
  }
  void skipped(const std::string& why) {
    ++skipped_;
    std::fprintf(stderr, "naneye recon: pair skipped: %s\n", why.c_str());
  }
  long long pairs() const { return pairs_; }
  void finish() {
    if (json_) {
      // The last line: a summary object (it has "summary", where a pair has "pair").
      nlohmann::json sum = {{"pairs", pairs_}, {"found", found_}, {"not_found", pairs_ - found_}};
      if (skipped_) sum["skipped"] = skipped_;
      sum["failures"] = {{"outcome", outcomes_}, {"left", left_reasons_}, {"right", right_reasons_}};
      std::cout << nlohmann::json{{"summary", sum}}.dump() << "\n";
    }
    std::cout.flush();
    std::fprintf(stderr, "naneye recon: %lld pairs, board found in %lld", pairs_, found_);
    if (skipped_) std::fprintf(stderr, ", %lld skipped (unreadable)", skipped_);
    std::fprintf(stderr, "\n");
    for (const auto& [why, n] : outcomes_) std::fprintf(stderr, "  not found: %lld %s\n", n, why.c_str());
    for (const auto& [why, n] : left_reasons_)
      std::fprintf(stderr, "    left eye: %lld %s\n", n, why.c_str());
    for (const auto& [why, n] : right_reasons_)
      std::fprintf(stderr, "    right eye: %lld %s\n", n, why.c_str());
  }

 private:
  bool json_;
  long long pairs_ = 0, found_ = 0, skipped_ = 0;
  // Pairs per reason (the pair's outcome and, per eye, the detector's), for the summary.
  std::map<std::string, long long> outcomes_, left_reasons_, right_reasons_;
};

// The flags as the step's settings (what naneyed reads from [board] and [pipeline]).
app::ProcessorSettings processor_settings(const ReconOptions& o) {
  app::ProcessorSettings s;
  recon::StereoReconstructorSettings& r = s.reconstructor;
  r.corners.board = parse_board(o.pattern, o.square_mm);
  r.reconstruction.corner_sigma_px = o.corner_sigma_px;
  r.tracking = !o.no_tracking;
  return s;
}

// The scene paths of one pair (--scene, --depth-out), the same for a source and for image files:
// sparse and dense on one demosaic and noise estimate, the depth PNGs, the pair's report.
class SceneStep {
 public:
  SceneStep(const ReconOptions& o, const recon::StereoRig& rig)
      : depth_out_(o.depth_out), calib_sigma_(rig.sigmas.covariance.has_value()) {
    if (!o.scene && depth_out_.empty()) return;
    sparse_ = std::make_unique<recon::scene::SparseReconstructor>(rig);
    dense_ = std::make_unique<recon::scene::DenseReconstructor>(rig);
    if (!depth_out_.empty()) std::filesystem::create_directories(depth_out_);
  }
  void run(const recon::RawImageView& left, const recon::RawImageView& right, unsigned long long pair) {
    if (!sparse_) return;
    sparse_->load_luma(left, right);
    sparse_->reconstruct(sparse_->luma(), sparse_result_);
    dense_->reconstruct(sparse_->luma(), depth_, &sparse_result_);
    if (!depth_out_.empty()) write_depth_pngs(depth_out_, pair, depth_, calib_sigma_, u16_);
  }
  void report(Report& report, const recon::PairResult& result) const {
    report.pair(result, sparse_ ? &sparse_result_ : nullptr, sparse_ ? &depth_ : nullptr);
  }

 private:
  std::string depth_out_;
  bool calib_sigma_;  // the calibration carries its covariance: calib-sigma PNGs too
  std::unique_ptr<recon::scene::SparseReconstructor> sparse_;
  std::unique_ptr<recon::scene::DenseReconstructor> dense_;
  recon::scene::SparseResult sparse_result_;
  recon::scene::DepthMap depth_;
  cv::Mat u16_;
};

// --fixed-pattern: the frames corrected in place before the board and the scene read them (the
// CLI owns its frames; naneyed corrects into buffers of its own and keeps the camera's).
class FixedPatternInPlace {
 public:
  FixedPatternInPlace(const ReconOptions& o, const recon::StereoRig& rig) {
    if (!o.fixed_pattern.empty())
      step_ = std::make_unique<app::FixedPatternStep>(o.fixed_pattern, rig.left.width(), rig.left.height());
  }
  void apply(int eye, std::uint16_t* pixels, const recon::RawImageView& view) {
    if (!step_) return;
    const recon::RawImageView fixed = step_->correct(eye, view);
    std::copy(fixed.data, fixed.data + static_cast<std::size_t>(view.width) * view.height, pixels);
  }

 private:
  // A pointer, not std::optional: GCC 12's -O1 (the ASan build) warned maybe-uninitialized on the
  // optional's string members once the unity batch inlined this.
  std::unique_ptr<app::FixedPatternStep> step_;
};

void run_recon_source(const ReconOptions& o, const recon::StereoRig& rig) {
  auto processor = app::make_processor(processor_settings(o));
  processor->set_rig(rig);
  auto source = app::make_source_registry().open(lossless_input_uri(o.input));
  source->start();
  auto result = std::make_unique<recon::PairResult>();
  SceneStep scene(o, rig);
  FixedPatternInPlace fixed(o, rig);
  Report report(o.json);
  for_each_pair(*source, o.max_pairs, [&](driver::StereoPair& pair) {
    fixed.apply(0, pair.left.pixels.data(), app::image_view(pair.left));
    fixed.apply(1, pair.right.pixels.data(), app::image_view(pair.right));
    processor->process(pair, *result);
    scene.run(app::image_view(pair.left), app::image_view(pair.right), result->pair);
    scene.report(report, *result);
  });
  source->stop();
  report.finish();
  if (auto err = source->error()) throw std::runtime_error(*err);
}

// Image pairs of any size: the recon step on views of the decoded images (a driver::Frame is
// 250 x 250 only, so these do not go through a FrameSource). Decoding allocates per image.
void run_recon_images(const ReconOptions& o, const recon::StereoRig& rig) {
  const auto pairs = image_pairs(o.left, o.right);
  driver::ImageSettings io;
  if (o.color != "mono" && o.color != "grbg") throw std::invalid_argument("--color: mono or grbg");
  io.color = o.color == "grbg" ? driver::ColorMode::bayer_grbg : driver::ColorMode::mono;
  recon::StereoReconstructor reconstructor(rig, processor_settings(o).reconstructor);
  SceneStep scene(o, rig);
  FixedPatternInPlace fixed(o, rig);
  auto result = std::make_unique<recon::PairResult>();
  driver::Image10 left, right;
  Report report(o.json);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (o.max_pairs >= 0 && report.pairs() >= o.max_pairs) break;
    try {
      driver::read_image(pairs[i].first, io, left);
      driver::read_image(pairs[i].second, io, right);
      for (const auto* im : {&left, &right})
        if (im->width != rig.left.width() || im->height != rig.left.height())
          throw driver::ImageError((im == &left ? pairs[i].first : pairs[i].second) + ": " +
                                   std::to_string(im->width) + " x " + std::to_string(im->height) +
                                   " pixels, but the calibration is for " + std::to_string(rig.left.width()) +
                                   " x " + std::to_string(rig.left.height()));
    } catch (const driver::ImageError& e) {
      report.skipped(e.what());
      continue;
    }
    *result = recon::PairResult{};
    result->pair = i;
    fixed.apply(0, left.pixels.data(), image_view(left));
    fixed.apply(1, right.pixels.data(), image_view(right));
    const recon::RawImageView lv = image_view(left), rv = image_view(right);
    reconstructor.process(lv, rv, *result);
    scene.run(lv, rv, i);
    scene.report(report, *result);
  }
  report.finish();
  if (report.pairs() == 0) throw std::runtime_error("no image pair could be read");
}

void run_recon(const ReconOptions& o) {
  if (o.input.empty() == o.left.empty())
    throw std::invalid_argument("give --input URI, or --left and --right image files (not both)");
  std::vector<std::filesystem::path> calib(o.calib.begin(), o.calib.end());
  const recon::StereoRig rig = recon::load_rig(calib);
  if (o.left.empty())
    run_recon_source(o, rig);
  else
    run_recon_images(o, rig);
}

}  // namespace

void add_recon_commands(CLI::App& app) {
  auto o = std::make_shared<ReconOptions>();
  auto* cmd =
      app.add_subcommand("recon", "3D points, board pose and the paper's P/D/R for every stereo pair");
  cmd->add_option("--calib", o->calib, "Calibration YAML (one file, or intrinsics and extrinsics)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--input", o->input,
                  "Source URI (file://, usb://, v4l2://, sim://, images://) or a capture path");
  cmd->add_option("--left", o->left,
                  "Left image files (PNG, JPEG, PGM, BMP, TIFF) or glob patterns, sorted by name; any size");
  cmd->add_option("--right", o->right, "Right image files or glob patterns, paired in order with --left");
  cmd->add_option("--color", o->color, "Image files hold mono frames or raw GRBG mosaics (mono, grbg)")
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "One JSON object per pair (the daemon's /v1/depth object)");
  cmd->add_option("--pattern", o->pattern, "Inner corners ROWSxCOLS")->capture_default_str();
  cmd->add_option("--square-mm", o->square_mm, "Square size")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--corner-sigma-px", o->corner_sigma_px, "Corner sigma when a pair cannot measure its own")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--no-tracking", o->no_tracking, "Full search on every pair");
  cmd->add_option("--max-pairs", o->max_pairs, "Stop after this many pairs (live sources)");
  cmd->add_flag("--scene", o->scene,
                "Also reconstruct whatever textured scene is in view: sparse points with depth sigmas "
                "(docs/scene.md); the JSON gains a \"scene\" object");
  cmd->add_option("--depth-out", o->depth_out,
                  "With the scene: write DIR/depth-NNNNNN.png and DIR/sigma-NNNNNN.png per pair (16-bit, "
                  "0.01 mm per unit on the left raw grid, 0 = no depth), and DIR/calib-sigma-NNNNNN.png "
                  "when the calibration carries its covariance; implies --scene");
  cmd->add_option("--fixed-pattern", o->fixed_pattern,
                  "The sensor's fixed pattern (naneye fixed-pattern), removed from both frames first")
      ->check(CLI::ExistingFile);
  cmd->callback([o] { run_recon(*o); });
}

}  // namespace naneye::tools
