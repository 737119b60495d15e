#include "naneye/recon/paper/division_rig.hpp"
#include "naneye/base/enum_table.hpp"

#include <Eigen/LU>

namespace naneye::recon {

namespace {
constexpr base::EnumTable<DivisionVariant, 2> kDivisionVariantNames{
    {{DivisionVariant::image_centre, "image_centre"}, {DivisionVariant::normalized, "normalized"}}};
}  // namespace

const char* to_string(DivisionVariant v) {
  return base::enum_name(kDivisionVariantNames, v);
}

Eigen::Vector3d DivisionCamera::ray(const Eigen::Vector2d& px) const {
  return K.inverse() * (model.A * model.lift(model.to_model(px)));
}

std::optional<Eigen::Vector2d> DivisionCamera::undistort_pixel(const Eigen::Vector2d& px) const {
  return model.undistort_pixel(px);
}

std::optional<Eigen::Vector2d> DivisionCamera::normalized(const Eigen::Vector2d& px) const {
  const auto u = undistort_pixel(px);
  if (!u) return std::nullopt;
  const Eigen::Vector3d xn = K.inverse() * u->homogeneous();
  return xn.head<2>() / xn.z();
}

std::optional<Eigen::Vector2d> DivisionCamera::project(const Eigen::Vector3d& X) const {
  if (!(X.z() > 0.0)) return std::nullopt;
  const Eigen::Vector3d u = K * (X / X.z());
  return model.distort_pixel(u.head<2>());
}

StereoRig DivisionRig::pinhole() const {
  StereoRig rig;
  rig.left = CameraModel(left.K, Distortion{});
  rig.right = CameraModel(right.K, Distortion{});
  rig.R = R;
  rig.T = T;
  return rig;
}

DivisionModel division_frame(const CameraModel& cam, DivisionVariant variant, double lambda) {
  return variant == DivisionVariant::image_centre
             ? DivisionModel::image_centred(lambda, cam.width(), cam.height())
             : DivisionModel::normalized(lambda, cam.K());
}

DivisionRig make_division_rig(const StereoRig& rig, DivisionVariant variant, double lambda_left,
                              double lambda_right) {
  DivisionRig out;
  out.left = {rig.left.K(), division_frame(rig.left, variant, lambda_left)};
  out.right = {rig.right.K(), division_frame(rig.right, variant, lambda_right)};
  out.R = rig.R;
  out.T = rig.T;
  return out;
}

}  // namespace naneye::recon
