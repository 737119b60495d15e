#pragma once
// The same id for the same physical corner in both eyes. The paper's 9 x 7 squares board looks the
// same turned by 180 degrees, so each eye's numbering (canonical_order) is only defined up to that
// turn. With a ~1 mm baseline both eyes see nearly the same image and usually agree; near the
// convention's switch (column axis at 45 degrees) they may not. The stereo geometry decides: the right
// numbering is the one whose correspondences satisfy the epipolar constraint x_r^T E x_l = 0 with
// positive depth in both cameras.
#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

enum class StereoIdStatus {
  consistent,     // the numbering already agreed
  flipped_right,  // the right eye's numbering was turned by 180 degrees to agree
  ambiguous,      // neither or both numberings fit the geometry: do not pair these detections
  not_found       // a detection is missing or the grids differ in size
};

const char* to_string(StereoIdStatus s);

struct StereoIdCheck {
  StereoIdStatus status = StereoIdStatus::not_found;
  double epipolar_rms_px = 0;        // of the accepted numbering (right image pixels)
  double epipolar_rms_other_px = 0;  // of the rejected one
  int pairs_used = 0;                // corners inside both models' domains
};

// Makes `right`'s numbering agree with `left`'s (turning it by 180 degrees when needed). A numbering
// fits when its epipolar RMS is at most max_epipolar_px and every corner has positive depth in both
// cameras.
StereoIdCheck resolve_stereo_ids(const StereoRig& rig, const CornerResult& left, CornerResult& right,
                                 double max_epipolar_px = 2.0);

// Turns a grid's numbering by 180 degrees (id k -> count - 1 - k).
void turn_numbering(CornerResult& r);

}  // namespace naneye::recon
