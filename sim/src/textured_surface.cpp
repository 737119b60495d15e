// Ray intersection and normals of the analytic surfaces of textured.hpp, and the presets.
#include <cmath>
#include <numbers>

#include "naneye/base/enum_table.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::sim {
namespace {

// Smallest root > eps of a t^2 + 2 b t + c = 0, or NaN.
double first_root(double a, double b, double c, double eps) {
  const double disc = b * b - a * c;
  if (!(disc >= 0.0) || a == 0.0) return NAN;
  const double s = std::sqrt(disc);
  const double t0 = (-b - s) / a, t1 = (-b + s) / a;
  if (t0 > eps) return t0;
  if (t1 > eps) return t1;
  return NAN;
}

double height(const Surface& s, double x, double y) {
  double h = 0;
  for (const auto& w : s.waves) h += w.amp_mm * std::sin(w.kx * x + w.ky * y + w.phase);
  return h;
}

Eigen::Vector2d height_gradient(const Surface& s, double x, double y) {
  Eigen::Vector2d g(0, 0);
  for (const auto& w : s.waves) {
    const double c = w.amp_mm * std::cos(w.kx * x + w.ky * y + w.phase);
    g += Eigen::Vector2d(c * w.kx, c * w.ky);
  }
  return g;
}

// Tube: the cylinder's wall up to `kTubeLength` along the axis from the origin, closed there by a
// disc (the far end of a tube the camera looks down).
constexpr double kTubeLength = 80.0;  // mm, the far limit

std::optional<double> intersect_height(const Surface& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  // Sphere tracing with a Lipschitz bound: |f(t + dt) - f(t)| <= (|dz| + L |dxy|) dt, L the largest
  // slope of h, so a step of |f| / (|dz| + L |dxy|) never jumps over the first root; then Newton.
  double slope = 0, amp = 0;
  for (const auto& w : s.waves) {
    slope += std::abs(w.amp_mm) * std::hypot(w.kx, w.ky);
    amp += std::abs(w.amp_mm);
  }
  const double dz = d.z();
  if (!(dz > 0.0)) return std::nullopt;
  const double lip = std::abs(dz) + slope * std::hypot(d.x(), d.y());
  auto f = [&](double t) {
    return s.origin.z() - (o.z() + t * dz) + height(s, o.x() + t * d.x(), o.y() + t * d.y());
  };
  // f > 0 in front of the surface (the camera side, Z smaller than the surface's).
  double t = std::max(0.0, (s.origin.z() - amp - o.z()) / dz);
  double v = f(t);
  if (v < 0) return std::nullopt;  // the origin lies behind the surface
  for (int i = 0; i < 400 && v > 1e-4; ++i) {
    t += v / lip;
    v = f(t);
    if (o.z() + t * dz > s.z_max_mm) return std::nullopt;
  }
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d g = height_gradient(s, o.x() + t * d.x(), o.y() + t * d.y());
    const double df = -dz + g.x() * d.x() + g.y() * d.y();
    if (df == 0.0) break;
    const double step = v / df;
    t -= step;
    v = f(t);
    if (std::abs(step) < 1e-13 * (1 + t)) break;
  }
  if (!(std::abs(v) < 1e-9) || !(t > 0)) return std::nullopt;
  return t;
}

}  // namespace

namespace {
constexpr base::EnumTable<SurfaceKind, 4> kSurfaceKindNames{{{SurfaceKind::plane, "plane"},
                                                             {SurfaceKind::sphere, "sphere"},
                                                             {SurfaceKind::tube, "tube"},
                                                             {SurfaceKind::height_field, "height_field"}}};
}  // namespace

const char* to_string(SurfaceKind k) {
  return base::enum_name(kSurfaceKindNames, k, "?");
}

std::optional<double> Surface::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  // A rigid motion keeps the ray parameter t: intersect the ray moved into the surface's frame.
  return intersect_local(to_local(o), pose_R.transpose() * d);
}

Eigen::Vector3d Surface::normal(const Eigen::Vector3d& X) const {
  return pose_R * normal_local(to_local(X));
}

std::optional<double> Surface::intersect_local(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  constexpr double kEps = 1e-9;
  double t = NAN;
  switch (kind) {
    case SurfaceKind::plane: {
      const double den = axis.dot(d);
      if (den != 0.0) t = axis.dot(origin - o) / den;
      if (!(t > kEps)) t = NAN;
      break;
    }
    case SurfaceKind::sphere: {
      const Eigen::Vector3d oc = o - origin;
      t = first_root(d.dot(d), oc.dot(d), oc.dot(oc) - radius_mm * radius_mm, kEps);
      break;
    }
    case SurfaceKind::tube: {
      // |(p - a) - ((p - a).u) u|^2 = r^2 with p = o + t d.
      const Eigen::Vector3d oc = o - origin;
      const Eigen::Vector3d dp = d - d.dot(axis) * axis, op = oc - oc.dot(axis) * axis;
      t = first_root(dp.dot(dp), op.dot(dp), op.dot(op) - radius_mm * radius_mm, kEps);
      if (std::isfinite(t) && (oc + t * d).dot(axis) > kTubeLength) {
        const double den = axis.dot(d);
        t = den > 0 ? (kTubeLength - oc.dot(axis)) / den : NAN;
      }
      break;
    }
    case SurfaceKind::height_field:
      return intersect_height(*this, o, d);
  }
  if (!std::isfinite(t)) return std::nullopt;
  return t;
}

Eigen::Vector3d Surface::normal_local(const Eigen::Vector3d& X) const {
  switch (kind) {
    case SurfaceKind::plane:
      return axis;
    case SurfaceKind::sphere:
      return (X - origin).normalized();
    case SurfaceKind::tube: {
      const Eigen::Vector3d p = X - origin;
      const double along = p.dot(axis);
      if (along >= kTubeLength - 1e-9) return axis;
      return (p - along * axis).normalized();
    }
    case SurfaceKind::height_field: {
      const Eigen::Vector2d g = height_gradient(*this, X.x(), X.y());
      return Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
    }
  }
  return axis;
}

namespace {
// Texture wavelengths ~4-20 px at depth z: a pixel spans z / f mm, f ~ 216 px (the paper's rigs).
TextureSettings texture_for(double z_mm, std::uint64_t seed) {
  TextureSettings t;
  const double px_mm = z_mm / 216.0;
  t.wavelength_min_mm = 4.0 * px_mm;
  t.wavelength_max_mm = 20.0 * px_mm;
  t.seed = seed;
  return t;
}
Eigen::Vector3d tilted(double about_x_deg, double about_y_deg) {
  const double a = about_x_deg * std::numbers::pi / 180, b = about_y_deg * std::numbers::pi / 180;
  return Eigen::Vector3d(std::sin(b), -std::sin(a) * std::cos(b), std::cos(a) * std::cos(b)).normalized();
}
}  // namespace

const std::vector<std::string>& textured_preset_names() {
  static const std::vector<std::string> names = {"plane", "plane-far", "sphere", "tube", "height"};
  return names;
}

std::optional<TexturedSceneSettings> textured_preset(const std::string& name) {
  TexturedSceneSettings s;
  Surface& f = s.surface;
  if (name == "plane") {
    f.kind = SurfaceKind::plane;
    f.origin = {0, 0, 20};
    f.axis = tilted(30, 15);
    s.texture = texture_for(20, 11);
    s.light_reference_mm = 20;
  } else if (name == "plane-far") {
    f.kind = SurfaceKind::plane;
    f.origin = {0, 0, 55};
    f.axis = tilted(-15, 8);
    s.texture = texture_for(55, 12);
    s.light_reference_mm = 55;
  } else if (name == "sphere") {
    f.kind = SurfaceKind::sphere;
    f.origin = {1.0, -1.0, 32};
    f.radius_mm = 20;
    s.texture = texture_for(15, 13);
    s.light_reference_mm = 14;
  } else if (name == "tube") {
    f.kind = SurfaceKind::tube;
    f.origin = {0.5, -0.3, 0};
    f.axis = Eigen::Vector3d(0.1, 0.05, 1).normalized();
    f.radius_mm = 7;
    s.texture = texture_for(12, 14);
    s.light_reference_mm = 10;
  } else if (name == "height") {
    f.kind = SurfaceKind::height_field;
    f.origin = {0, 0, 15};
    const double k = 2 * std::numbers::pi;
    f.waves = {{0.8, k / 8 * 0.8, k / 8 * 0.6, 0.3},
               {0.5, -k / 5 * 0.3, k / 5 * 0.95, 1.1},
               {0.2, k / 4 * 0.9, -k / 4 * 0.44, 2.0}};
    f.z_min_mm = 10;
    f.z_max_mm = 20;
    s.texture = texture_for(15, 15);
    s.light_reference_mm = 15;
  } else {
    return std::nullopt;
  }
  return s;
}

}  // namespace naneye::sim
