#pragma once
// The whole per-pair path for a stream of raw stereo frames: detect the board in both eyes
// (tracked from the previous pair when possible), make the corner ids agree between the eyes, then
// reconstruct_pair(). Keeps the state a stream needs (previous detections); allocates nothing per pair
// once warmed up (the full search is our own; only its opt-in OpenCV fallback would allocate).
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/stereo_ids.hpp"
#include "naneye/recon/pair/reconstruction.hpp"

namespace naneye::recon {

struct StereoReconstructorSettings {
  CornerSettings corners;
  ReconstructionSettings reconstruction;
  double max_epipolar_px = 2.0;  // for resolve_stereo_ids
  bool tracking = true;
};

// Why a pair has no board, for logs and counters.
enum class PairOutcome { board_found, no_board_left, no_board_right, ids_ambiguous, pose_failed };
const char* to_string(PairOutcome o);

class StereoReconstructor {
 public:
  StereoReconstructor(const StereoRig& rig, const StereoReconstructorSettings& settings);

  // Fills `out` (except pair index and timestamps). Returns what happened; out.board_found is true
  // only for PairOutcome::board_found.
  PairOutcome process(const RawImageView& left, const RawImageView& right, PairResult& out);

  // A new calibration (the daemon's SIGHUP): the next pair is searched afresh.
  void set_rig(const StereoRig& rig);
  const StereoRig& rig() const { return rig_; }
  const StereoReconstructorSettings& settings() const { return settings_; }

  // The detections behind the last result (ids agreeing between the eyes when both were found).
  const CornerResult& left_corners() const { return left_; }
  const CornerResult& right_corners() const { return right_; }

 private:
  StereoRig rig_;
  StereoReconstructorSettings settings_;
  CornerDetector left_detector_, right_detector_;
  CornerResult left_, right_, previous_left_, previous_right_;
  bool have_previous_ = false;
  std::array<CornerObservation, kMaxCorners> observations_{};
};

}  // namespace naneye::recon
