#include "naneye/daemon/rig_check.hpp"

#include <cmath>
#include <sstream>

namespace naneye::daemon {
namespace {

// The sane domain, wide enough for any NanEye calibration and narrow enough to refuse typos and
// garbage. Units and reasons:
//  - focal length 10..10000 px: the NanEye's is ~216 px (paper, Dataset 3); 10 px would be a
//    170-degree-wide pinhole over 250 px, 10000 px a 1.4-degree one.
//  - principal point inside the image (px): it is where the optical axis meets the die.
//  - |k1|, |k2|, |k3|, |p1|, |p2| <= 100 (normalized image units): the paper's are below 1; beyond
//    100 the polynomial folds within a fraction of a pixel of the centre.
//  - baseline 0.01..100 mm: the NanEye Stereo's is ~1.08 mm; 0 cannot triangulate.
//  - R a rotation: |R^T R - I| <= 1e-6 (a YAML written with 17 digits is within 1e-15), det > 0.
constexpr double kMinFocalPx = 10, kMaxFocalPx = 10000;
constexpr double kMaxDistortion = 100;
constexpr double kMinBaselineMm = 0.01, kMaxBaselineMm = 100;
constexpr double kRotationTolerance = 1e-6;

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::optional<std::string> camera_problem(const recon::CameraModel& c, const char* name, int sensor_px) {
  const std::string who = std::string(name) + " camera: ";
  if (c.width() != sensor_px || c.height() != sensor_px) {
    return who + "image size " + std::to_string(c.width()) + "x" + std::to_string(c.height()) +
           " does not match the " + std::to_string(sensor_px) + "x" + std::to_string(sensor_px) + " sensor";
  }
  if (!c.K().allFinite()) return who + "the camera matrix has a value that is not finite";
  if (c.K()(2, 0) != 0 || c.K()(2, 1) != 0 || c.K()(2, 2) != 1)
    return who + "the camera matrix's last row is not [0 0 1]";
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
  return std::nullopt;
}

}  // namespace

std::optional<std::string> rig_problem(const recon::StereoRig& rig, int sensor_px) {
  if (auto p = camera_problem(rig.left, "left", sensor_px)) return p;
  if (auto p = camera_problem(rig.right, "right", sensor_px)) return p;
  if (!rig.R.allFinite() || !rig.T.allFinite()) return "the relative pose has a value that is not finite";
  const double ortho = (rig.R.transpose() * rig.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho > kRotationTolerance || rig.R.determinant() <= 0)
    return "R is not a rotation (|R^T R - I| = " + num(ortho) + ", det " + num(rig.R.determinant()) + ")";
  const double b = rig.baseline_mm();
  if (!(b >= kMinBaselineMm && b <= kMaxBaselineMm))
    return "baseline " + num(b) + " mm outside " + num(kMinBaselineMm) + ".." + num(kMaxBaselineMm) + " mm";
  return std::nullopt;
}

}  // namespace naneye::daemon
