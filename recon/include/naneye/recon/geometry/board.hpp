#pragma once
// The calibration target, stated once: every settings struct that needs the board holds one of these.
#include <Eigen/Core>
#include <string>

namespace naneye::recon {

// A chessboard's inner-corner grid. Corner (row, col) sits at (col * square, row * square, 0) in the
// board frame (origin at the first inner corner, x along a row, z = 0 on the board), as OpenCV's object
// points; corner k is row-major (k = row * cols + col). Defaults: the paper's board (Dias et al.,
// ICDSC 2016, Dataset 3), 9 x 7 squares of 5.99 mm held landscape, so 6 x 8 inner corners.
struct BoardGeometry {
  int rows = 6, cols = 8;   // inner corners
  double square_mm = 5.99;  // side of one square

  int count() const { return rows * cols; }
  Eigen::Vector3d corner(int row, int col) const { return {col * square_mm, row * square_mm, 0.0}; }
  Eigen::Vector3d corner(int k) const { return corner(k / cols, k % cols); }
  // The centre of the inner grid in board coordinates.
  Eigen::Vector3d centre() const { return {0.5 * (cols - 1) * square_mm, 0.5 * (rows - 1) * square_mm, 0.0}; }

  // Empty when usable, otherwise what is wrong, naming the field: at least 2 x 2 inner corners (one
  // square needs four corners to fix a plane) and a finite positive square size.
  std::string check() const;
};

}  // namespace naneye::recon
