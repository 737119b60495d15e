#include "naneye/recon/corners/stereo_ids.hpp"
#include "naneye/base/enum_table.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace naneye::recon {

namespace {
constexpr base::EnumTable<StereoIdStatus, 4> kStereoIdStatusNames{
    {{StereoIdStatus::consistent, "consistent"},
     {StereoIdStatus::flipped_right, "flipped_right"},
     {StereoIdStatus::ambiguous, "ambiguous"},
     {StereoIdStatus::not_found, "not_found"}}};
}  // namespace

const char* to_string(StereoIdStatus s) {
  return base::enum_name(kStereoIdStatusNames, s);
}

void turn_numbering(CornerResult& r) {
  std::reverse(r.corners.begin(), r.corners.begin() + r.count);
  for (int i = 0; i < r.count; ++i) {
    r.corners[static_cast<std::size_t>(i)].row = i / r.cols;
    r.corners[static_cast<std::size_t>(i)].col = i % r.cols;
  }
}

namespace {

struct Score {
  double rms_px = 0;
  bool positive_depth = true;
  int used = 0;
};

// Epipolar distance in the right image (Hartley & Zisserman Sec. 9.6: l_r = E x_l) and the depths of
// the two rays' closest approach (lambda_r x_r = lambda_l R x_l + T in least squares).
Score score(const StereoRig& rig, const CornerResult& left, const CornerResult& right, bool turned) {
  const Eigen::Matrix3d E = rig.essential();
  Score s;
  double sum = 0;
  for (int i = 0; i < left.count; ++i) {
    const int j = turned ? right.count - 1 - i : i;
    const Corner& cl = left.corners[static_cast<std::size_t>(i)];
    const Corner& cr = right.corners[static_cast<std::size_t>(j)];
    if ((cl.flags | cr.flags) & kCornerBeyondFold) continue;
    const Undistorted ul = rig.left.undistort(cl.px), ur = rig.right.undistort(cr.px);
    if (!ul.ok() || !ur.ok()) continue;
    const Eigen::Vector3d xl(ul.normalized.x(), ul.normalized.y(), 1.0);
    const Eigen::Vector3d xr(ur.normalized.x(), ur.normalized.y(), 1.0);
    const Eigen::Vector3d l = E * xl;
    const double d = std::abs(xr.dot(l)) / std::max(l.head<2>().norm(), 1e-12) * rig.right.fx();
    sum += d * d;
    ++s.used;
    Eigen::Matrix<double, 3, 2> A;
    A.col(0) = rig.R * xl;
    A.col(1) = -xr;
    const Eigen::Vector2d lam = (A.transpose() * A).inverse() * (A.transpose() * (-rig.T));
    if (!(lam.x() > 0 && lam.y() > 0)) s.positive_depth = false;
  }
  s.rms_px = s.used ? std::sqrt(sum / s.used) : 0.0;
  return s;
}

}  // namespace

StereoIdCheck resolve_stereo_ids(const StereoRig& rig, const CornerResult& left, CornerResult& right,
                                 double max_epipolar_px) {
  StereoIdCheck out;
  if (!left.found || !right.found || left.rows != right.rows || left.cols != right.cols ||
      left.count != right.count || left.count == 0) {
    return out;
  }
  const Score keep = score(rig, left, right, false), turn = score(rig, left, right, true);
  out.pairs_used = keep.used;
  const bool keep_ok = keep.used >= 4 && keep.positive_depth && keep.rms_px <= max_epipolar_px;
  const bool turn_ok = turn.used >= 4 && turn.positive_depth && turn.rms_px <= max_epipolar_px;
  if (keep_ok == turn_ok) {
    out.status = StereoIdStatus::ambiguous;
    out.epipolar_rms_px = keep.rms_px;
    out.epipolar_rms_other_px = turn.rms_px;
    return out;
  }
  if (keep_ok) {
    out.status = StereoIdStatus::consistent;
    out.epipolar_rms_px = keep.rms_px;
    out.epipolar_rms_other_px = turn.rms_px;
  } else {
    turn_numbering(right);
    out.status = StereoIdStatus::flipped_right;
    out.epipolar_rms_px = turn.rms_px;
    out.epipolar_rms_other_px = keep.rms_px;
  }
  return out;
}

}  // namespace naneye::recon
