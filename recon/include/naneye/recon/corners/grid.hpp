#pragma once
// The coarse grid and the whole-grid checks of the corner detector (corners.hpp).
#include <vector>

#include <Eigen/Core>

#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/refine.hpp"

namespace naneye::recon {

// Full search for a rows x cols grid of inner corners with OpenCV (findChessboardCorners with
// adaptive threshold, then findChessboardCornersSB), on an 8-bit stretch of the luminance. Fills
// `coarse` row-major (cols per row). `gray8` is a reusable buffer.
bool coarse_grid_opencv(const LumaView& img, int rows, int cols, std::vector<unsigned char>& gray8,
                        std::vector<Eigen::Vector2f>& coarse);

// +1 / -1: which diagonal pair of quadrants around corner (row, col) is the brighter one, sampled
// from the image along the grid directions; 0 when unclear. A true checkerboard alternates.
int corner_polarity(const LumaView& img, const CornerResult& r, int row, int col);
// The same test at a point p with grid steps dc (to the next column) and dr (to the next row), raw
// pixels: what the coarse lattice uses to tell X-junctions from the border squares' L- and
// T-junctions before any fit. Squares too small for samples at 0.35 of the diagonal (a far board)
// are sampled at their centres when `square_centres` (the steps are the board's, not a false link's).
int quadrant_polarity(const LumaView& img, const Eigen::Vector2d& p, const Eigen::Vector2d& dc,
                      const Eigen::Vector2d& dr, bool square_centres = true);
// Whether the grid line through an X-junction at p runs on for a whole step beyond the board: u is
// the grid step pointing away from the board (the row or column that would come next), v the other
// step. A larger board's next row has squares there, so the line between them carries the board's
// contrast (opposite in sign to the line between the last squares inside, -u) from the junction to
// the next one; clutter that happens to make an X at the junction (a bright object beside the
// margin) does not run straight along the grid line for a step. Returns true when it does, or when
// the samples cannot tell (out of the image, or squares too small to sample beside the edges).
bool grid_line_continues(const LumaView& img, const Eigen::Vector2d& p, const Eigen::Vector2d& u,
                         const Eigen::Vector2d& v);

}  // namespace naneye::recon
