#include "naneye/recon/camera/rig_validate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace naneye::recon {
namespace {

// The sane domain, wide enough for any NanEye calibration and narrow enough to refuse typos and
// garbage. Units and reasons:
//  - image side 16..4096 px: the NanEye's is 250; every consumer builds per-pixel maps and tables
//    (4096^2 px is ~17 M entries per map, the most a calibration may make a process allocate).
//  - focal length 10..10000 px: the NanEye's is ~216 px (paper, Dataset 3); 10 px would be a
//    170-degree-wide pinhole over 250 px, 10000 px a 1.4-degree one.
//  - principal point inside the image (px): it is where the optical axis meets the die.
//  - |k1|, |k2|, |k3|, |p1|, |p2| <= 100 (normalized image units): the paper's are below 1; beyond
//    100 the polynomial folds within a fraction of a pixel of the centre.
//  - the fold of the radial model (the edge of the valid domain) at least a tenth of the image's
//    shorter side from the principal point (px): the paper's left camera folds at 139 px of 250;
//    a fold at 25 px leaves ~3 % of the pixels measurable, a fold closer in is a broken model.
//  - baseline 0.01..100 mm: the NanEye Stereo's is ~1.08 mm; 0 cannot triangulate.
//  - R a rotation: |R^T R - I| <= 1e-6 (a YAML written with 17 digits is within 1e-15), det > 0.
constexpr int kMinSidePx = 16, kMaxSidePx = 4096;
constexpr double kMinFocalPx = 10, kMaxFocalPx = 10000;
constexpr double kMaxDistortion = 100;
constexpr double kMinFoldShareOfSide = 0.1;
constexpr double kMinBaselineMm = 0.01, kMaxBaselineMm = 100;
constexpr double kRotationTolerance = 1e-6;

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::optional<std::string> camera_problem(const CameraModel& c, const char* name) {
  const std::string who = std::string(name) + " camera: ";
  for (int side : {c.width(), c.height()}) {
    if (side < kMinSidePx || side > kMaxSidePx)
      return who + "image size " + std::to_string(c.width()) + "x" + std::to_string(c.height()) +
             " outside " + std::to_string(kMinSidePx) + ".." + std::to_string(kMaxSidePx) + " px a side";
  }
  if (!c.K().allFinite()) return who + "the camera matrix has a value that is not finite";
  if (c.K()(1, 0) != 0 || c.K()(2, 0) != 0 || c.K()(2, 1) != 0 || c.K()(2, 2) != 1)
    return who + "the camera matrix is not upper triangular with [0 0 1] last";
  for (double f : {c.fx(), c.fy()}) {
    if (!(f >= kMinFocalPx && f <= kMaxFocalPx))
      return who + "focal length " + num(f) + " px outside " + num(kMinFocalPx) + ".." + num(kMaxFocalPx);
  }
  if (!(c.cx() >= -0.5 && c.cx() <= c.width() - 0.5 && c.cy() >= -0.5 && c.cy() <= c.height() - 0.5))
    return who + "principal point (" + num(c.cx()) + ", " + num(c.cy()) + ") outside the image";
  const auto& d = c.distortion();
  for (double k : {d.k1, d.k2, d.p1, d.p2, d.k3}) {
    if (!std::isfinite(k)) return who + "a distortion coefficient is not finite";
    if (std::abs(k) > kMaxDistortion)
      return who + "distortion coefficient " + num(k) + " beyond +-" + num(kMaxDistortion);
  }
  const double min_fold = kMinFoldShareOfSide * std::min(c.width(), c.height());
  if (const auto fold = c.fold_radius_px(); fold && !(*fold >= min_fold))
    return who + "the distortion model folds " + num(*fold) +
           " px from the principal point (valid domain under " + num(min_fold) + " px)";
  return std::nullopt;
}

}  // namespace

std::optional<std::string> rig_problem(const StereoRig& rig) {
  if (auto p = camera_problem(rig.left, "left")) return p;
  if (auto p = camera_problem(rig.right, "right")) return p;
  if (!rig.R.allFinite() || !rig.T.allFinite()) return "the relative pose has a value that is not finite";
  const double ortho = (rig.R.transpose() * rig.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho > kRotationTolerance || rig.R.determinant() <= 0)
    return "R is not a rotation (|R^T R - I| = " + num(ortho) + ", det " + num(rig.R.determinant()) + ")";
  const double b = rig.baseline_mm();
  if (!(b >= kMinBaselineMm && b <= kMaxBaselineMm))
    return "baseline " + num(b) + " mm outside " + num(kMinBaselineMm) + ".." + num(kMaxBaselineMm) + " mm";
  return std::nullopt;
}

}  // namespace naneye::recon
