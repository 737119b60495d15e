#pragma once
// The per-pair processing step the pipeline runs on its worker thread. The product's step
// (detect -> undistort -> triangulate -> board pose -> metrics) is assembled from recon/ and drops in
// here; the daemon only depends on this interface.
#include <memory>
#include <string_view>

#include "naneye/daemon/scene_result.hpp"
#include "naneye/daemon/settings.hpp"
#include "naneye/driver/frame.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/pair/result.hpp"
#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"

namespace naneye::daemon {

class PairProcessor {
 public:
  virtual ~PairProcessor() = default;
  // Called on the worker thread before the first pair and again between pairs after a reload.
  virtual void set_rig(const recon::StereoRig& rig) = 0;
  // Fills `out` (a preallocated slot that still holds an older result: overwrite every field).
  // Must not allocate: it runs once per pair.
  virtual void process(const driver::StereoPair& pair, recon::PairResult& out) = 0;
  // The whole step as the pipeline runs it: the board into `out` and, in [recon] mode scene or
  // both, the scene into `scene` and the dense map into `depth` (when given; the pipeline hands a
  // slot of its own). Board-only steps clear `scene`. Must not allocate once `reserve` was called.
  virtual void process_pair(const driver::StereoPair& pair, recon::PairResult& out, SceneResult& scene,
                            recon::scene::DepthMap* depth) {
    (void)depth;
    process(pair, out);
    scene.clear();
  }
  // True when process_pair computes the scene, and a dense map.
  virtual bool scene() const { return false; }
  virtual bool dense() const { return false; }
  // Gives a result slot's buffers the capacity process_pair fills (called once per slot).
  virtual void reserve(SceneResult& scene, recon::scene::DepthMap* depth) const {
    (void)scene;
    (void)depth;
  }
  // Shown in the log and /v1/status.
  virtual std::string_view name() const = 0;
};

// The processing step naneyed and `naneye recon` run: recon::StereoReconstructor on both raw frames
// (the board of settings' [board] section).
std::unique_ptr<PairProcessor> make_processor(const Settings& settings);

// The reconstructor's settings for the [board] and [pipeline] sections (what make_processor uses;
// `naneye recon --left/--right` runs recon::StereoReconstructor on images of any size with them).
recon::StereoReconstructorSettings reconstructor_settings(const Settings& settings);

// A driver frame as the recon module sees it (no copy).
recon::RawImageView image_view(const driver::Frame& frame);

// Copies the pair's identity and timestamps into `out` and clears everything else.
void fill_pair_identity(const driver::StereoPair& pair, recon::PairResult& out);

}  // namespace naneye::daemon
