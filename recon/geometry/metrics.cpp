#include "naneye/recon/geometry/metrics.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace naneye::recon {

namespace {

bool valid(const Eigen::Vector3d& X) {
  return X.allFinite();
}

// The plane through three points; empty when they are (numerically) collinear.
std::optional<Plane> plane_through(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a, v = c - a;
  const Eigen::Vector3d n = u.cross(v);
  const double nn = n.norm();
  if (!(nn > 1e-12 * u.norm() * v.norm())) return std::nullopt;
  Plane p;
  p.normal = n / nn;
  p.offset = -p.normal.dot(a);
  return p;
}

std::optional<double> mean_of_finite(std::span<const double> values) {
  double sum = 0.0;
  int n = 0;
  for (double v : values) {
    if (std::isfinite(v)) {
      sum += v;
      ++n;
    }
  }
  if (n == 0) return std::nullopt;
  return sum / n;
}

void check_grid(std::span<const Eigen::Vector3d> grid, int rows, int cols) {
  if (rows < 1 || cols < 1 ||
      grid.size() != static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols)) {
    throw std::invalid_argument("grid size does not match rows x cols");
  }
}

}  // namespace

namespace {

// fit_plane for at most MaxRows valid points (Eigen::Dynamic: any number). With a fixed maximum the
// matrix and the SVD's work space live on the stack: the per-pair path allocates nothing.
template <int MaxRows>
std::optional<Plane> fit_plane_max(std::span<const Eigen::Vector3d> points, std::size_t valid_count) {
  if (valid_count < 3) return std::nullopt;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& X : points)
    if (valid(X)) centroid += X;
  centroid /= static_cast<double>(valid_count);
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::ColMajor, MaxRows, 3>;
  Matrix A(static_cast<Eigen::Index>(valid_count), 3);
  Eigen::Index row = 0;
  for (const auto& X : points)
    if (valid(X)) A.row(row++) = (X - centroid).transpose();
  const Eigen::JacobiSVD<Matrix> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  // Collinear (or coincident) points: the two smallest singular values both vanish.
  if (!(s(1) > 1e-12 * s(0))) return std::nullopt;
  Plane p;
  p.normal = svd.matrixV().col(2).normalized();
  p.offset = -p.normal.dot(centroid);
  return p;
}

constexpr int kStackPoints = 64;  // a whole board's corners (pair_result.hpp's kMaxCorners)

}  // namespace

std::optional<Plane> fit_plane(std::span<const Eigen::Vector3d> points) {
  const auto n = static_cast<std::size_t>(std::count_if(points.begin(), points.end(), valid));
  return n <= kStackPoints ? fit_plane_max<kStackPoints>(points, n)
                           : fit_plane_max<Eigen::Dynamic>(points, n);
}

std::optional<double> planarity_error(std::span<const Eigen::Vector3d> points) {
  const std::optional<Plane> plane = fit_plane(points);
  if (!plane) return std::nullopt;
  double sum = 0.0;
  int n = 0;
  for (const auto& X : points) {
    if (!valid(X)) continue;
    sum += std::abs(plane->signed_distance(X));
    ++n;
  }
  return sum / n;
}

std::size_t neighbour_distance_errors(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                      double square_mm, std::span<double> out) {
  check_grid(grid, rows, cols);
  const auto count = static_cast<std::size_t>(rows * (cols - 1) + cols * (rows - 1));
  if (out.size() < count) throw std::invalid_argument("neighbour_distance_errors: output span too small");
  const auto at = [&](int r, int c) -> const Eigen::Vector3d& {
    return grid[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)];
  };
  const auto error = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    if (!valid(a) || !valid(b)) return std::numeric_limits<double>::quiet_NaN();
    return std::abs((a - b).norm() - square_mm);
  };
  std::size_t k = 0;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c + 1 < cols; ++c) out[k++] = error(at(r, c), at(r, c + 1));
  }
  for (int c = 0; c < cols; ++c) {
    for (int r = 0; r + 1 < rows; ++r) out[k++] = error(at(r, c), at(r + 1, c));
  }
  return k;
}

std::vector<double> neighbour_distance_errors(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                              double square_mm) {
  check_grid(grid, rows, cols);
  std::vector<double> out(static_cast<std::size_t>(rows * (cols - 1) + cols * (rows - 1)));
  neighbour_distance_errors(grid, rows, cols, square_mm, out);
  return out;
}

std::optional<double> distance_error(std::span<const Eigen::Vector3d> grid, int rows, int cols,
                                     double square_mm) {
  check_grid(grid, rows, cols);
  // A whole board's neighbour pairs fit on the stack (the per-pair path allocates nothing).
  std::array<double, 2 * kStackPoints> buffer;
  const auto count = static_cast<std::size_t>(rows * (cols - 1) + cols * (rows - 1));
  if (count <= buffer.size()) {
    const std::size_t n = neighbour_distance_errors(grid, rows, cols, square_mm, buffer);
    return mean_of_finite(std::span<const double>(buffer.data(), n));
  }
  const std::vector<double> errors = neighbour_distance_errors(grid, rows, cols, square_mm);
  return mean_of_finite(errors);
}

std::vector<double> median_filter3(std::span<const double> values) {
  const std::size_t n = values.size();
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = values[i == 0 ? 0 : i - 1];
    const double b = values[i];
    const double c = values[i + 1 < n ? i + 1 : n - 1];
    out[i] = std::max(std::min(a, b), std::min(std::max(a, b), c));
  }
  return out;
}

std::optional<double> distance_error_median_filtered(std::span<const Eigen::Vector3d> grid, int rows,
                                                     int cols, double square_mm) {
  const std::vector<double> errors = neighbour_distance_errors(grid, rows, cols, square_mm);
  // errors holds rows sequences of (cols - 1) horizontal pairs, then cols sequences of (rows - 1)
  // vertical pairs; filter each run of valid values within a sequence on its own.
  std::vector<double> filtered;
  filtered.reserve(errors.size());
  const auto filter_sequence = [&](std::size_t begin, std::size_t length) {
    std::size_t i = begin;
    const std::size_t end = begin + length;
    while (i < end) {
      if (!std::isfinite(errors[i])) {
        ++i;
        continue;
      }
      std::size_t j = i;
      while (j < end && std::isfinite(errors[j])) ++j;
      const std::vector<double> run = median_filter3(std::span<const double>(errors.data() + i, j - i));
      filtered.insert(filtered.end(), run.begin(), run.end());
      i = j;
    }
  };
  const std::size_t h = static_cast<std::size_t>(cols - 1), v = static_cast<std::size_t>(rows - 1);
  for (std::size_t r = 0; r < static_cast<std::size_t>(rows); ++r) filter_sequence(r * h, h);
  const std::size_t vertical_begin = static_cast<std::size_t>(rows) * h;
  for (std::size_t c = 0; c < static_cast<std::size_t>(cols); ++c) filter_sequence(vertical_begin + c * v, v);
  return mean_of_finite(filtered);
}

std::optional<double> reprojection_error(const StereoRig& rig, std::span<const Eigen::Vector3d> points,
                                         std::span<const Eigen::Vector2d> px_left,
                                         std::span<const Eigen::Vector2d> px_right) {
  if (px_left.size() != points.size() || px_right.size() != points.size()) {
    throw std::invalid_argument("reprojection_error: points and pixel lists differ in size");
  }
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& X = points[i];
    if (!valid(X) || !px_left[i].allFinite() || !px_right[i].allFinite()) continue;
    sum += (rig.left.project(X) - px_left[i]).norm();
    sum += (rig.right.project(rig.R * X + rig.T) - px_right[i]).norm();
    n += 2;
  }
  if (n == 0) return std::nullopt;
  return sum / n;
}

std::optional<RansacPlane> fit_plane_ransac(std::span<const Eigen::Vector3d> points,
                                            const RansacSettings& settings) {
  std::vector<std::size_t> idx;  // indices of the valid points
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (valid(points[i])) idx.push_back(i);
  }
  const std::size_t n = idx.size();
  if (n < 3) return std::nullopt;

  std::optional<Plane> best;
  int best_count = -1;
  double best_sum = 0.0;
  const auto score = [&](std::size_t a, std::size_t b, std::size_t c) {
    const std::optional<Plane> cand = plane_through(points[idx[a]], points[idx[b]], points[idx[c]]);
    if (!cand) return;
    const double threshold = settings.threshold_ratio * cand->distance_from_origin();
    int count = 0;
    double sum = 0.0;
    for (std::size_t i : idx) {
      const double d = std::abs(cand->signed_distance(points[i]));
      if (d <= threshold) {
        ++count;
        sum += d;
      }
    }
    if (count > best_count || (count == best_count && sum < best_sum)) {
      best = cand;
      best_count = count;
      best_sum = sum;
    }
  };
  if (n <= static_cast<std::size_t>(settings.exhaustive_max_points)) {
    for (std::size_t a = 0; a < n; ++a) {
      for (std::size_t b = a + 1; b < n; ++b) {
        for (std::size_t c = b + 1; c < n; ++c) score(a, b, c);
      }
    }
  } else {
    std::mt19937 rng(settings.seed);
    std::uniform_int_distribution<std::size_t> pick(0, n - 1);
    for (int it = 0; it < settings.iterations; ++it) {
      const std::size_t a = pick(rng), b = pick(rng), c = pick(rng);
      if (a == b || b == c || a == c) continue;
      score(a, b, c);
    }
  }
  if (!best) return std::nullopt;

  RansacPlane out;
  out.inliers.assign(points.size(), false);
  std::vector<Eigen::Vector3d> inlier_points;
  const double threshold = settings.threshold_ratio * best->distance_from_origin();
  for (std::size_t i : idx) {
    if (std::abs(best->signed_distance(points[i])) <= threshold) {
      out.inliers[i] = true;
      inlier_points.push_back(points[i]);
    }
  }
  out.inlier_count = static_cast<int>(inlier_points.size());
  const std::optional<Plane> refit = fit_plane(inlier_points);
  out.plane = refit ? *refit : *best;
  double sum = 0.0;
  for (const auto& X : inlier_points) sum += std::abs(out.plane.signed_distance(X));
  out.mean_inlier_distance = sum / static_cast<double>(inlier_points.size());
  return out;
}

}  // namespace naneye::recon
