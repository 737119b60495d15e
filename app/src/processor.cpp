#include "naneye/app/processor.hpp"

#include <opencv2/core/utility.hpp>
#include <optional>

#include "naneye/app/fixed_pattern_step.hpp"
#include "naneye/app/helper_thread.hpp"
#include "naneye/app/scene_json.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::app {

void fill_pair_identity(const driver::StereoPair& pair, recon::PairResult& out) {
  out.pair = pair.index;
  out.t_left_ns = pair.left.sensor_ns;
  out.t_right_ns = pair.right.sensor_ns;
  out.reference_left = driver::to_string(pair.left.reference);
  out.reference_right = driver::to_string(pair.right.reference);
  out.board_found = false;
  out.point_count = 0;
  out.board.reset();
  out.metrics.reset();
}

recon::RawImageView image_view(const driver::Frame& f) {
  recon::RawImageView v;
  v.data = f.pixels.data();
  v.width = v.height = v.stride = driver::kSensorSize;
  v.layout =
      f.color == driver::ColorMode::bayer_grbg ? recon::PixelLayout::bayer_grbg : recon::PixelLayout::mono;
  return v;
}

namespace {

// board.detect = false: every pair is published with its timing and frames, and no board.
class TimingOnly final : public PairProcessor {
 public:
  void set_rig(const recon::StereoRig&) override {}
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    fill_pair_identity(pair, out);
  }
  std::string_view name() const override { return "timing only (board.detect = false)"; }
};

// How the board's corners are triangulated, in the words of the status line.
std::string method_text(recon::TriangulationMethod m) {
  if (m == recon::TriangulationMethod::refined) return "niter2 + refinement";
  return recon::to_string(m);
}

// What the step does, for the log and /v1/status: the board's triangulation as configured.
std::string step_name(const ProcessorSettings& s) {
  if (s.mode == ReconMode::board)
    return "board reconstruction (corners, " + method_text(s.reconstructor.reconstruction.method) +
           ", board pose)";
  const std::string dense = s.threads > 1 ? "dense depth map on a second thread" : "dense depth map";
  if (s.mode == ReconMode::scene) return "scene reconstruction (sparse features, " + dense + ")";
  return "board and scene reconstruction (corners, board pose; sparse features, " + dense + ")";
}

// The product's processing step: the board (issue #5: both eyes' corners, triangulation, board
// pose, P/D/R) and/or the textured scene (issue 14: sparse points, the dense map), per [recon] mode.
// Board and scene run on the same pair; the scene's two paths share one luminance.
class Reconstruction final : public PairProcessor {
 public:
  explicit Reconstruction(const ProcessorSettings& s)
      : settings_(s),
        name_(step_name(s)),
        board_wanted_(s.mode != ReconMode::scene),
        scene_wanted_(s.mode != ReconMode::board) {
    if (!s.fixed_pattern.empty()) {
      fixed_.emplace(s.fixed_pattern, driver::kSensorSize, driver::kSensorSize);
      name_ += "; " + fixed_->description();
    }
  }

  void set_rig(const recon::StereoRig& rig) override {
    if (board_wanted_) {
      if (board_)
        board_->set_rig(rig);
      else
        board_.emplace(rig, settings_.reconstructor);
    }
    // Built anew (its masks and rays depend on the rig): on a reload this runs on the caller's
    // thread (Pipeline::reload), never between two pairs of the worker.
    if (scene_wanted_) {
      sparse_.emplace(rig, settings_.sparse);
      dense_.emplace(rig);
      map_pixels_ = static_cast<std::size_t>(rig.left.width()) * static_cast<std::size_t>(rig.left.height());
      // The dense map beside the sparse points only when it does not start from their band.
      if (settings_.threads > 1 && !dense_->settings().band_from_sparse && !helper_)
        helper_.emplace([this] {
          dense_->reconstruct(sparse_->luma(), *helper_depth_, nullptr);
          if (board_) board_->process(left_, right_, *helper_board_);
        });
    }
  }
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    fill_pair_identity(pair, out);
    views(pair);
    if (board_) board_->process(left_, right_, out);
  }
  void process_pair(const driver::StereoPair& pair, recon::PairResult& out, SceneResult& scene,
                    recon::scene::DepthMap* depth) override {
    if (!sparse_) {
      process(pair, out);
      scene.clear();
      return;
    }
    fill_pair_identity(pair, out);
    views(pair);
    scene.clear();
    // One demosaic and one luminance for both scene paths.
    sparse_->load_luma(left_, right_);
    const bool dense = dense_ && depth;  // dense_: empty only after a set_rig that threw
    if (helper_ && dense) {
      // The dense map and the board on the helper while this thread reads the sparse points (the
      // longer part: balanced so, a pair takes ~the sparse path's time). They share only what all
      // read (the luminance, the frames), and the helper is done before any of it changes
      // (finish() even when this half throws).
      helper_depth_ = depth;
      helper_board_ = &out;
      helper_->start();
      try {
        sparse(scene);
      } catch (...) {
        try {
          helper_->finish();
        } catch (...) {  // the sparse half's error is the one reported
        }
        throw;
      }
      helper_->finish();
    } else {
      if (board_) board_->process(left_, right_, out);
      sparse(scene);
      if (dense) dense_->reconstruct(sparse_->luma(), *depth, &scene.sparse);
    }
    if (dense) {
      scene.dense = true;
      scene.depth = summarize(*depth);
    }
  }
  bool scene() const override { return scene_wanted_; }
  bool dense() const override { return scene_wanted_; }
  void reserve(SceneResult& scene, recon::scene::DepthMap* depth) const override {
    if (!scene_wanted_) return;
    scene.sparse.points.reserve(static_cast<std::size_t>(settings_.sparse.max_features));
    if (depth) {
      depth->z_mm.reserve(map_pixels_);
      depth->sigma_mm.reserve(map_pixels_);
      depth->calib_sigma_mm.reserve(map_pixels_);
    }
  }
  std::string_view name() const override { return name_; }

 private:
  void sparse(SceneResult& scene) {
    sparse_->reconstruct(sparse_->luma(), scene.sparse);
    scene.computed = true;
  }

  // The frames every path reads: the pair's own, or with the sensor's fixed pattern removed.
  void views(const driver::StereoPair& pair) {
    left_ = image_view(pair.left);
    right_ = image_view(pair.right);
    if (!fixed_) return;
    left_ = fixed_->correct(0, left_);
    right_ = fixed_->correct(1, right_);
  }

  ProcessorSettings settings_;
  std::string name_;
  bool board_wanted_, scene_wanted_;
  std::optional<recon::StereoReconstructor> board_;
  std::optional<recon::scene::SparseReconstructor> sparse_;
  std::optional<recon::scene::DenseReconstructor> dense_;
  std::size_t map_pixels_ = 0;  // the left raw grid's, for the dense maps' capacity
  std::optional<FixedPatternStep> fixed_;
  recon::RawImageView left_, right_;
  recon::scene::DepthMap* helper_depth_ = nullptr;  // what the helper fills for this pair
  recon::PairResult* helper_board_ = nullptr;
  // Last: its destructor waits for the helper before the reconstructors it uses go.
  std::optional<HelperThread> helper_;
};

}  // namespace

std::unique_ptr<PairProcessor> make_processor(const ProcessorSettings& settings) {
  if (!settings.detect) return std::make_unique<TimingOnly>();
  // OpenCV's own thread pool (TBB workers that spin while idle) only takes the other core from the
  // capture and HTTP threads: measured, it tripled naneyed's time per pair on 2 cores (and its
  // uninstrumented threads blind ThreadSanitizer). The step's one second thread ([recon] threads,
  // HelperThread) sleeps in a futex between pairs.
  cv::setNumThreads(1);
  return std::make_unique<Reconstruction>(settings);
}

}  // namespace naneye::app
