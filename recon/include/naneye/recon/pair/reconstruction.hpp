#pragma once
// One stereo pair's corners -> one PairResult: exact undistortion (points beyond a model's
// fold are flagged, not used), triangulation (niter2 + raw-pixel refinement) with a depth sigma from
// the corner noise measured on this very pair, the board pose from both eyes, and the paper's P, D, R
// over the triangulated points.
#include <span>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/geometry/board_pose.hpp"
#include "naneye/recon/geometry/triangulation.hpp"
#include "naneye/recon/pair/result.hpp"

namespace naneye::recon {

struct ReconstructionSettings {
  TriangulationMethod method = TriangulationMethod::refined;
  // Corner sigma used when it cannot be measured (fewer residuals than parameters + 2), and the floor
  // of the measured one: no corner is more precise than this.
  double corner_sigma_px = 0.05;
  double min_corner_sigma_px = 0.01;
};

// `obs` holds the board's corners as both eyes saw them, ids consistent between the eyes (row-major
// over the inner grid; a corner an eye could not use has *_ok false). Fills `out` except pair and
// timestamps; out.board_found is true when the board pose could be estimated. Allocates nothing.
void reconstruct_pair(const StereoRig& rig, const BoardGeometry& board,
                      const ReconstructionSettings& settings, std::span<const CornerObservation> obs,
                      PairResult& out);

// The corner sigma this pair's own residuals support: the board-pose RMS with the 6 pose parameters
// taken out of the degrees of freedom, sqrt(cost / (n - 6)) over the n pixel coordinates; never below
// the settings' floor.
double measured_corner_sigma(const BoardPose& pose, const ReconstructionSettings& settings);

}  // namespace naneye::recon
