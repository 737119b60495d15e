#include "naneye/recon/camera/rig.hpp"

#include <cmath>

namespace naneye::recon {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Eigen::Matrix3d rodrigues(const Eigen::Vector3d& om) {
  const double angle = om.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, om / angle).toRotationMatrix();
}

Eigen::Vector3d rodrigues(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d StereoRig::essential() const {
  return skew(T) * R;
}

}  // namespace naneye::recon
