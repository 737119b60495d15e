#pragma once
// What the simulated cameras look at: a planar checkerboard at a pose, lit by a light beside the
// lens, in front of a dim background. Units: millimetres; the left camera's frame is the world.
#include <Eigen/Core>
#include <vector>

#include "naneye/recon/geometry/board.hpp"

namespace naneye::sim {

// The board is recon's (naneye/recon/geometry/board.hpp: the paper's 9 x 7 squares, 6 x 8 inner
// corners, as OpenCV's object points); the renderer adds only its white margin.
using recon::BoardGeometry;

// Board pose: X_left_camera = R X_board + t (mm).
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t{0, 0, 50};
};

struct SceneSettings {
  BoardGeometry board;
  double border_squares = 0.5;  // white margin around the squares, in squares
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
  // Pixels an edge crosses integrate n^2 points of a rank-1 lattice over their area (every point
  // on its own row and column: edges resolved to 1/n^2 px); uniform pixels need one. See docs.
  int supersample = 16;
  bool board_present = true;  // false renders the background only
};

}  // namespace naneye::sim
