#pragma once
// What the simulated cameras look at: a planar checkerboard at a pose, lit by a light beside the
// lens, in front of a dim background. Units: millimetres; the left camera's frame is the world.
#include <Eigen/Core>
#include <vector>

namespace naneye::sim {

// A board of square_rows x square_cols squares (the paper's 9 x 7 board, held landscape: 7 rows of
// 9 squares), so (square_rows - 1) x (square_cols - 1) inner corners. Board coordinates: origin at
// the first inner corner (top-left), u along a row of corners (columns), v down the columns (rows),
// z = 0 on the board; inner corner (i, j) sits at (j s, i s, 0), as OpenCV's object points.
struct BoardGeometry {
  int square_rows = 7;
  int square_cols = 9;
  double square_mm = 5.99;
  double border_squares = 0.5;  // white margin around the squares, in squares

  int inner_rows() const { return square_rows - 1; }
  int inner_cols() const { return square_cols - 1; }
  int inner_count() const { return inner_rows() * inner_cols(); }
  // Inner corner k (row-major over the inner grid) in board coordinates.
  Eigen::Vector3d corner(int k) const;
  // The centre of the inner grid in board coordinates.
  Eigen::Vector3d centre() const;
};

// Board pose: X_left_camera = R X_board + t (mm).
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t{0, 0, 50};
};

struct SceneSettings {
  BoardGeometry board;
  // Reflectances relative to the white squares (printed matte board) and the background radiance
  // relative to a white square facing the camera at light_reference_mm.
  double white = 1.0;
  double black = 0.07;
  double background = 0.12;
  // The light beside the lens: irradiance ~ cos(incidence) / d^2 (point source), normalised to 1
  // for a board facing the camera on axis at light_reference_mm. Off: uniform illumination.
  bool lighting = true;
  Eigen::Vector3d light_mm{0.6, -0.9, 0.0};
  double light_reference_mm = 70.0;
  // Samples per pixel side: each pixel integrates n x n points spread over its area.
  int supersample = 4;
  bool board_present = true;  // false renders the background only
};

}  // namespace naneye::sim
