#pragma once
// The paper's evaluation criteria (Dias et al., ICDSC 2016, Sec. 4.1 "Evaluation Criteria") and the
// robust variants of its cross-validation section ("Evaluation Based on Cross-Validation"):
//   P  planarity: least-squares plane, mean point-to-plane distance (mm);
//   D  3D distance: mean |distance between grid neighbours - square size| (mm);
//   R  reprojection: mean distance of the reprojected points from the measured raw pixels (px).
// A point is invalid (skipped everywhere) when any coordinate is not finite; Triangulated::X of a
// refused pair is NaN, so reconstructions can be passed in as they are. Functions return an empty
// optional when nothing valid is left to average.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon {

// normal . X + offset = 0 with |normal| = 1.
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0.0;
  double signed_distance(const Eigen::Vector3d& X) const { return normal.dot(X) + offset; }
  double distance_from_origin() const { return offset < 0.0 ? -offset : offset; }
};

// Total least squares over the valid points: the plane through their centroid whose normal is the
// right singular vector of the smallest singular value of the centred points. Empty for fewer than
// three valid points or when they are collinear. Allocates nothing for up to 64 valid points.
std::optional<Plane> fit_plane(std::span<const Eigen::Vector3d> points);

// P: mean |distance| of the valid points to their least-squares plane.
std::optional<double> planarity_error(std::span<const Eigen::Vector3d> points);

// The |distance - square_mm| of every horizontal and vertical neighbour pair of a rows x cols grid
// stored row-major, in the order: all horizontal pairs row by row, then all vertical pairs column
// by column. A pair with an invalid end gives NaN.
std::vector<double> neighbour_distance_errors(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                              double square_mm);

// The same written into `out` (at least rows * (cols - 1) + cols * (rows - 1) values, else
// std::invalid_argument); returns the number written. Allocates nothing: the per-pair path's form.
std::size_t neighbour_distance_errors(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                      double square_mm, std::span<double> out);

// D: the mean of the valid neighbour_distance_errors. Allocates nothing for grids up to 64 corners.
std::optional<double> distance_error(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                     double square_mm);

// 1-D median filter with a window of 3; the ends repeat their value (the border mode of
// scipy.ndimage.median_filter's default "reflect" and of cv::medianBlur), so out[0] =
// median(v0, v0, v1).
std::vector<double> median_filter3(std::span<const double> values);

// D after the paper's median filter on the distance errors. The paper gives no details; our
// reading: the neighbour-distance errors form one sequence per grid row (horizontal pairs, left
// to right) and one per grid column (vertical pairs, top to bottom); a pair with an invalid end
// splits its sequence into runs; each run goes through median_filter3 and the mean of all filtered
// values is D. A single bad corner spoils two consecutive errors of a sequence, so a window of 3
// alone does not remove it, but a single bad edge (one outlying error) is removed.
std::optional<double> distance_error_median_filtered(std::span<const Eigen::Vector3d> grid, int rows,
                                                     int cols, double square_mm);

// R: mean over the valid points and both images of |project(X) - measured pixel| (raw pixels).
// points, px_left and px_right must have the same size (std::invalid_argument otherwise).
std::optional<double> reprojection_error(const StereoRig& rig, std::span<const Eigen::Vector3d> points,
                                         std::span<const Eigen::Vector2d> px_left,
                                         std::span<const Eigen::Vector2d> px_right);

struct RansacSettings {
  // Inlier threshold as a share of the candidate plane's distance from the origin (the paper: 15 %).
  double threshold_ratio = 0.15;
  // Up to this many valid points every triple is tried (deterministic and exhaustive);
  // beyond it `iterations` random triples from std::mt19937(seed).
  int exhaustive_max_points = 64;
  int iterations = 2000;
  std::uint32_t seed = 20160101u;
};

struct RansacPlane {
  Plane plane;                // refit (total least squares) on the inliers
  std::vector<bool> inliers;  // one per input point; invalid points are never inliers
  int inlier_count = 0;
  double mean_inlier_distance = 0.0;  // P over the inliers, to the refit plane
};

// The cross-validation section's RANSAC plane fit. Candidate planes come from triples of valid
// points; the best has the most inliers (|distance| <= threshold_ratio * its distance from the
// origin), ties broken by the smaller sum of inlier distances. Its inliers are then refit.
// Empty for fewer than three valid points or when every triple is collinear.
std::optional<RansacPlane> fit_plane_ransac(std::span<const Eigen::Vector3d> points,
                                            const RansacSettings& settings = {});

}  // namespace naneye::recon
