#include "naneye/daemon/processor.hpp"

#include <opencv2/core/utility.hpp>
#include <optional>

#include "naneye/recon/stereo_reconstructor.hpp"

namespace naneye::daemon {

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

recon::StereoReconstructorSettings reconstructor_settings(const Settings& s) {
  recon::StereoReconstructorSettings r;
  r.corners.rows = s.board_rows;
  r.corners.cols = s.board_cols;
  r.reconstruction.board.square_mm = s.square_mm;
  r.reconstruction.corner_sigma_px = s.corner_sigma_px;
  r.tracking = s.tracking;
  return r;
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

// The product's processing step (issue #5): both eyes' corners, triangulation, board pose, P/D/R.
class BoardReconstruction final : public PairProcessor {
 public:
  explicit BoardReconstruction(const Settings& s) : settings_(reconstructor_settings(s)) {}

  void set_rig(const recon::StereoRig& rig) override {
    if (reconstructor_)
      reconstructor_->set_rig(rig);
    else
      reconstructor_.emplace(rig, settings_);
  }
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    fill_pair_identity(pair, out);
    if (reconstructor_) reconstructor_->process(image_view(pair.left), image_view(pair.right), out);
  }
  std::string_view name() const override {
    return "board reconstruction (corners, niter2 + refinement, board pose)";
  }

 private:
  recon::StereoReconstructorSettings settings_;
  std::optional<recon::StereoReconstructor> reconstructor_;
};

}  // namespace

std::unique_ptr<PairProcessor> make_processor(const Settings& settings) {
  if (!settings.detect) return std::make_unique<TimingOnly>();
  // The per-pair step is written for one core. OpenCV's own thread pool (TBB workers that spin while
  // idle) only takes the other core from the capture and HTTP threads: measured, it tripled naneyed's
  // time per pair on 2 cores (and its uninstrumented threads blind ThreadSanitizer).
  cv::setNumThreads(1);
  return std::make_unique<BoardReconstruction>(settings);
}

}  // namespace naneye::daemon
