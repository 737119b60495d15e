// Board geometry and the exact truth of a pose: the corners, projected by recon's camera model.
#include <cmath>

#include "naneye/driver/wire_format.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {

namespace {

// A corner is imaged when it lies in front of the camera and inside the valid domain: undistorting
// its projection must give back its own ray. A point beyond the fold projects to a folded-back pixel
// whose undistortion fails or is another ray.
bool imaged(const recon::CameraModel& cam, const Eigen::Vector3d& X, const Eigen::Vector2d& px) {
  if (!(X.z() > 0.0)) return false;
  const Eigen::Vector2d xn = X.head<2>() / X.z();
  const recon::Undistorted u = cam.undistort(px);
  return u.ok() && (u.normalized - xn).norm() <= 1e-7 * (1.0 + xn.norm());
}

bool in_active_area(const Eigen::Vector2d& px) {
  const double last = driver::kSensorSize - 1;
  if (!(px.x() >= 0.0 && px.y() >= 0.0 && px.x() <= last - 1.0 && px.y() <= last)) return false;
  return !(px.y() > last - 0.5 && px.x() > last - 2.5);  // row 249 columns 248-249 are padding
}

}  // namespace

Truth compute_truth(const recon::StereoRig& rig, const BoardGeometry& board, const Pose& pose,
                    bool board_present) {
  Truth t;
  t.pose = pose;
  t.board_present = board_present;
  const int n = board.count();
  t.corners_mm.resize(n);
  t.left_px.resize(n);
  t.right_px.resize(n);
  t.left_imaged.assign(n, false);
  t.right_imaged.assign(n, false);
  t.left_in_view.assign(n, false);
  t.right_in_view.assign(n, false);
  bool all = board_present;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d X = pose.R * board.corner(k) + pose.t;
    const Eigen::Vector3d Xr = rig.R * X + rig.T;
    t.corners_mm[k] = X;
    t.left_px[k] = rig.left.project(X);
    t.right_px[k] = rig.right.project(Xr);
    t.left_imaged[k] = imaged(rig.left, X, t.left_px[k]);
    t.right_imaged[k] = imaged(rig.right, Xr, t.right_px[k]);
    t.left_in_view[k] = board_present && t.left_imaged[k] && in_active_area(t.left_px[k]);
    t.right_in_view[k] = board_present && t.right_imaged[k] && in_active_area(t.right_px[k]);
    all = all && t.left_in_view[k] && t.right_in_view[k];
  }
  t.board_in_view = all;
  return t;
}

}  // namespace naneye::sim
