#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/base/enum_table.hpp"

#include <span>

namespace naneye::recon {

namespace {
constexpr base::EnumTable<PairOutcome, 5> kPairOutcomeNames{{{PairOutcome::board_found, "board_found"},
                                                             {PairOutcome::no_board_left, "no_board_left"},
                                                             {PairOutcome::no_board_right, "no_board_right"},
                                                             {PairOutcome::ids_ambiguous, "ids_ambiguous"},
                                                             {PairOutcome::pose_failed, "pose_failed"}}};
}  // namespace

const char* to_string(PairOutcome o) {
  return base::enum_name(kPairOutcomeNames, o);
}

StereoReconstructor::StereoReconstructor(const StereoRig& rig, const StereoReconstructorSettings& settings)
    : rig_(rig),
      settings_(settings),
      left_detector_(rig.left, settings.corners),
      right_detector_(rig.right, settings.corners) {}

void StereoReconstructor::set_rig(const StereoRig& rig) {
  rig_ = rig;
  left_detector_ = CornerDetector(rig.left, settings_.corners);
  right_detector_ = CornerDetector(rig.right, settings_.corners);
  have_previous_ = false;
}

PairOutcome StereoReconstructor::process(const RawImageView& left, const RawImageView& right,
                                         PairResult& out) {
  out.board_found = false;
  out.board.reset();
  out.metrics.reset();
  out.point_count = 0;
  out.failure = out.failure_left = out.failure_right = nullptr;

  const bool track = settings_.tracking && have_previous_;
  const bool found_left = left_detector_.detect(left, track ? &previous_left_ : nullptr, left_);
  const bool found_right = right_detector_.detect(right, track ? &previous_right_ : nullptr, right_);
  have_previous_ = false;
  out.failure_left = to_string(left_detector_.last_failure());
  out.failure_right = to_string(right_detector_.last_failure());
  const auto fail = [&out](PairOutcome o) {
    out.failure = to_string(o);
    return o;
  };
  // A board seen by one eye only is not reported: its corners could not be triangulated, and a
  // monocular pose would be a different product with other error bars.
  if (!found_left) return fail(PairOutcome::no_board_left);
  if (!found_right) return fail(PairOutcome::no_board_right);
  const StereoIdCheck ids = resolve_stereo_ids(rig_, left_, right_, settings_.max_epipolar_px);
  if (ids.status != StereoIdStatus::consistent && ids.status != StereoIdStatus::flipped_right)
    return fail(PairOutcome::ids_ambiguous);

  // Corners a detector flags (beyond the fold, poor fit) are kept in the result but not used.
  const std::uint8_t unusable = kCornerBeyondFold | kCornerFitPoor;
  const int n = std::min(left_.count, right_.count);
  for (int i = 0; i < n; ++i) {
    const Corner& l = left_.corners[static_cast<std::size_t>(i)];
    const Corner& r = right_.corners[static_cast<std::size_t>(i)];
    CornerObservation& o = observations_[static_cast<std::size_t>(i)];
    o.row = l.row;
    o.col = l.col;
    o.left_px = l.px;
    o.right_px = r.px;
    o.left_ok = (l.flags & unusable) == 0;
    o.right_ok = (r.flags & unusable) == 0;
  }
  reconstruct_pair(rig_, settings_.corners.board, settings_.reconstruction,
                   std::span<const CornerObservation>(observations_.data(), static_cast<std::size_t>(n)),
                   out);
  if (!out.board_found) return fail(PairOutcome::pose_failed);
  out.failure_left = out.failure_right = nullptr;
  previous_left_ = left_;
  previous_right_ = right_;
  have_previous_ = true;
  return PairOutcome::board_found;
}

}  // namespace naneye::recon
