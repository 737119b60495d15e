#include "naneye/recon/paper/division_model.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

namespace naneye::recon {

DivisionModel DivisionModel::image_centred(double lambda, int width, int height) {
  DivisionModel m;
  m.lambda = lambda;
  // Pixel centres at integers: the image spans [-0.5, width - 0.5], its centre is (width - 1) / 2.
  m.A(0, 2) = 0.5 * (width - 1);
  m.A(1, 2) = 0.5 * (height - 1);
  return m;
}

DivisionModel DivisionModel::normalized(double lambda, const Eigen::Matrix3d& K) {
  if (K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0 || !(K(0, 0) > 0.0) || !(K(1, 1) > 0.0)) {
    throw std::invalid_argument("division model: K must be [fx s cx; 0 fy cy; 0 0 1]");
  }
  DivisionModel m;
  m.lambda = lambda;
  m.A = K;
  return m;
}

Eigen::Vector2d DivisionModel::to_model(const Eigen::Vector2d& px) const {
  // A is affine and upper triangular: invert by substitution rather than a general solve.
  const double y = (px.y() - A(1, 2)) / A(1, 1);
  return {(px.x() - A(0, 2) - A(0, 1) * y) / A(0, 0), y};
}

Eigen::Vector2d DivisionModel::to_pixel(const Eigen::Vector2d& x) const {
  return A.topLeftCorner<2, 2>() * x + A.topRightCorner<2, 1>();
}

std::optional<double> DivisionModel::max_distorted_radius() const {
  if (lambda == 0.0) return std::nullopt;
  return 1.0 / std::sqrt(std::abs(lambda));
}

bool DivisionModel::in_domain(const Eigen::Vector2d& xd) const {
  return std::isfinite(xd.x()) && std::isfinite(xd.y()) && std::abs(lambda) * xd.squaredNorm() < 1.0;
}

Eigen::Vector3d DivisionModel::lift(const Eigen::Vector2d& xd) const {
  return {xd.x(), xd.y(), 1.0 + lambda * xd.squaredNorm()};
}

std::optional<Eigen::Vector2d> DivisionModel::undistort(const Eigen::Vector2d& xd) const {
  if (!in_domain(xd)) return std::nullopt;
  return xd / (1.0 + lambda * xd.squaredNorm());
}

std::optional<double> division_distort_radius(double lambda, double r_u) {
  const double disc = 1.0 - 4.0 * lambda * r_u * r_u;
  if (!(disc >= 0.0)) return std::nullopt;
  return 2.0 * r_u / (1.0 + std::sqrt(disc));
}

std::optional<Eigen::Vector2d> DivisionModel::distort(const Eigen::Vector2d& xu) const {
  const double ru = xu.norm();
  if (!std::isfinite(ru)) return std::nullopt;
  if (ru == 0.0) return xu;
  const auto rd = division_distort_radius(lambda, ru);
  if (!rd) return std::nullopt;
  return xu * (*rd / ru);
}

std::optional<Eigen::Vector2d> DivisionModel::undistort_pixel(const Eigen::Vector2d& px) const {
  const auto xu = undistort(to_model(px));
  if (!xu) return std::nullopt;
  return to_pixel(*xu);
}

std::optional<Eigen::Vector2d> DivisionModel::distort_pixel(const Eigen::Vector2d& px_u) const {
  const auto xd = distort(to_model(px_u));
  if (!xd) return std::nullopt;
  return to_pixel(*xd);
}

}  // namespace naneye::recon
