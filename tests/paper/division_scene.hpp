#pragma once
// Shared scenes for the division-model tests: the paper's Dataset 3 rig and chessboards at known poses.
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/geometry/board_pose.hpp"
#include "naneye/recon/paper/division_model.hpp"
#include "naneye/recon/paper/division_rig.hpp"

namespace division_test {

using namespace naneye::recon;

inline StereoRig rig_d3() {
  return load_rig(std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml");
}

struct BoardPlacement {
  Eigen::Matrix3d R;  // board -> left camera
  Eigen::Vector3d t;
};

// A 6 x 8 board, tilted, its centre on the left optical axis at z_mm, shifted by (dx, dy) mm.
inline BoardPlacement place_board(double tilt_x_deg, double tilt_y_deg, double z_mm, double dx = 0,
                                  double dy = 0, const BoardGeometry& b = {}) {
  BoardPlacement s;
  s.R = (Eigen::AngleAxisd(tilt_y_deg * M_PI / 180, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(tilt_x_deg * M_PI / 180, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  const Eigen::Vector3d centre = b.centre();
  s.t = Eigen::Vector3d(dx, dy, z_mm) - s.R * centre;
  return s;
}

// Nineteen placements in the spirit of the paper's Dataset 3 (5.99 mm squares, 58-85 mm away).
inline std::vector<BoardPlacement> dataset3_boards(const BoardGeometry& b) {
  std::vector<BoardPlacement> out;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> tilt(-35, 35), z(58, 85), shift(-8, 8);
  for (int i = 0; i < 19; ++i)
    out.push_back(place_board(tilt(rng), tilt(rng), z(rng), shift(rng), shift(rng), b));
  return out;
}

// The plane n^T X = d (left frame) of a placement, and its induced homography on normalized points:
// X_right = (R + T n^T / d) X_left for X_left on the plane.
inline Eigen::Matrix3d plane_homography(const StereoRig& rig, const BoardPlacement& s) {
  const Eigen::Vector3d n = s.R.col(2);
  const double d = n.dot(s.t);
  return rig.R + rig.T * n.transpose() / d;
}

// The 6 x 8 board at a placement as a division rig sees it, with Gaussian pixel noise when rng is given.
struct Views {
  std::vector<Eigen::Vector3d> truth;
  std::vector<Eigen::Vector2d> left, right;
};

inline Views render(const DivisionRig& rig, const BoardPlacement& s, double noise_px = 0,
                    std::mt19937* rng = nullptr) {
  const BoardGeometry b;
  std::normal_distribution<double> n(0, noise_px);
  Views v;
  for (int r = 0; r < b.rows; ++r) {
    for (int c = 0; c < b.cols; ++c) {
      const Eigen::Vector3d X = s.R * b.corner(r, c) + s.t;
      v.truth.push_back(X);
      v.left.push_back(*rig.left.project(X) +
                       (rng ? Eigen::Vector2d(n(*rng), n(*rng)) : Eigen::Vector2d::Zero()));
      v.right.push_back(*rig.right.project(rig.R * X + rig.T) +
                        (rng ? Eigen::Vector2d(n(*rng), n(*rng)) : Eigen::Vector2d::Zero()));
    }
  }
  return v;
}

// Renders a point with pinhole K and a division model (the truth of the division tests).
struct DivisionEye {
  Eigen::Matrix3d K;
  DivisionModel model;
  // Distorted model coordinates of the camera-frame point X.
  Eigen::Vector2d project_model(const Eigen::Vector3d& X) const {
    const Eigen::Vector3d px = K * (X / X.z());
    return *model.distort(model.to_model(px.head<2>()));
  }
  Eigen::Vector2d project_px(const Eigen::Vector3d& X) const { return model.to_pixel(project_model(X)); }
};

inline DivisionEye eye(const CameraModel& cam, DivisionModel m) {
  return {cam.K(), m};
}

}  // namespace division_test
