#pragma once
// The per-pair processing step naneyed's worker and `naneye recon` run. The product's step
// (detect -> undistort -> triangulate -> board pose -> metrics, and the textured scene) is assembled
// from recon/ here; the daemon's pipeline only depends on the PairProcessor interface.
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "naneye/app/scene_result.hpp"
#include "naneye/base/enum_table.hpp"
#include "naneye/driver/frame.hpp"
#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/pair/result.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::app {

// What the step reconstructs per pair (naneyed's [recon] mode): the board (corners, pose, P/D/R),
// the textured scene (sparse points and the dense depth map, docs/scene.md), or both on the same pair.
enum class ReconMode { board, scene, both };
inline constexpr base::EnumTable<ReconMode, 3> kReconModeNames{
    {{ReconMode::board, "board"}, {ReconMode::scene, "scene"}, {ReconMode::both, "both"}}};
const char* to_string(ReconMode m);

// The step's settings: the recon structs themselves (their defaults are the product's), read from
// naneyed's [board], [pipeline] and [recon] sections or from `naneye recon`'s flags.
struct ProcessorSettings {
  // [board] detect: false serves frames and timing only (a rig without a target in view).
  bool detect = true;
  // [recon] mode: board until the scene path fits the 62 fps budget: sparse alone takes 17-31 ms per
  // pair today (docs/scene.md), so "both" would drop every other pair of a live camera.
  ReconMode mode = ReconMode::board;
  // [recon] threads: 2 computes the scene's dense map (and the board) on a thread of its own while
  // the worker reads the sparse points, so a pair takes the longer of the two instead of their sum
  // (docs/scene.md, "Two threads"); 1 keeps the whole step on the worker's core. Scene modes only.
  int threads = 2;
  // [board] rows, cols, square_mm (corners.board),
  // tracking; [pipeline] corner_sigma_px (reconstruction.corner_sigma_px).
  recon::StereoReconstructorSettings reconstructor;
  recon::scene::SparseSettings sparse;
  // [sensor] fixed_pattern: the file `naneye fixed-pattern` wrote; its maps are removed from both
  // frames before the board and the scene read them (docs/sensor-calibration.md). Empty: none.
  std::filesystem::path fixed_pattern;

  // Empty when usable, otherwise what is wrong, naming naneyed's key ("board.rows: ...").
  std::string check() const;
};

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
// and, per `settings.mode`, the scene. Loads settings.fixed_pattern: std::runtime_error naming the
// file when it cannot be used.
std::unique_ptr<PairProcessor> make_processor(const ProcessorSettings& settings);

// A driver frame as the recon module sees it (no copy).
recon::RawImageView image_view(const driver::Frame& frame);

// Copies the pair's identity and timestamps into `out` and clears everything else.
void fill_pair_identity(const driver::StereoPair& pair, recon::PairResult& out);

}  // namespace naneye::app
