#include "naneye/recon/paper/division_fit.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace naneye::recon {
namespace {

struct Sample {
  Eigen::Vector2d raw, pinhole;  // p and u = K x_n, both pixels
};

std::vector<Sample> sample_camera(const CameraModel& cam, int step) {
  if (step < 1) throw std::invalid_argument("division fit: step_px must be >= 1");
  std::vector<Sample> out;
  for (int v = 0; v < cam.height(); v += step) {
    for (int u = 0; u < cam.width(); u += step) {
      const Eigen::Vector2d p(u, v);
      const Undistorted und = cam.undistort(p);
      if (!und.ok()) continue;
      out.push_back({p, cam.to_pixel(und.normalized)});  // to_pixel of an undistorted point = K x_n
    }
  }
  return out;
}

double sum_sq(const DivisionModel& m, const std::vector<Sample>& s) {
  double acc = 0;
  for (const auto& x : s) {
    const auto d = m.distort_pixel(x.pinhole);
    acc += d ? (*d - x.raw).squaredNorm() : 1e12;
  }
  return acc;
}

}  // namespace

DivisionFit division_residuals(const CameraModel& cam, const DivisionModel& model, int step_px) {
  DivisionFit fit;
  fit.model = model;
  fit.lambda = model.lambda;
  const Eigen::Vector2d centre = model.to_pixel({0.0, 0.0});
  double acc = 0;
  for (const auto& s : sample_camera(cam, step_px)) {
    const auto d = model.distort_pixel(s.pinhole);
    if (!d) continue;
    const double r = (*d - s.raw).norm();
    fit.samples.push_back({(s.raw - centre).norm(), r});
    acc += r * r;
    fit.max_px = std::max(fit.max_px, r);
  }
  fit.samples_used = static_cast<int>(fit.samples.size());
  fit.ok = fit.samples_used > 0;
  fit.rms_px = fit.ok ? std::sqrt(acc / fit.samples_used) : 0.0;
  return fit;
}

DivisionFit fit_division_to_camera(const CameraModel& cam, DivisionVariant variant, int step_px) {
  const std::vector<Sample> samples = sample_camera(cam, step_px);
  DivisionModel m = division_frame(cam, variant, 0.0);
  if (samples.size() < 2) return {};
  // Start: Eq. 7 multiplied out, (1 + lambda r_d^2) x_u = x_d, is linear in lambda:
  // lambda r_d^2 x_u = x_d - x_u (model coordinates).
  double num = 0, den = 0;
  for (const auto& s : samples) {
    const Eigen::Vector2d xd = m.to_model(s.raw), xu = m.to_model(s.pinhole);
    const double r2 = xd.squaredNorm();
    num += r2 * xu.dot(xd - xu);
    den += r2 * r2 * xu.squaredNorm();
  }
  if (!(den > 0.0)) return {};
  m.lambda = num / den;
  // Gauss-Newton on the raw-pixel residual in lambda alone (central-difference derivative), halving steps
  // that do not lower the cost.
  double cost = sum_sq(m, samples);
  for (int it = 0; it < 50; ++it) {
    const double h = 1e-6 * std::max(std::abs(m.lambda), 1e-12);
    DivisionModel mp = m, mm = m;
    mp.lambda += h;
    mm.lambda -= h;
    double g = 0, jj = 0;
    for (const auto& s : samples) {
      const auto d0 = m.distort_pixel(s.pinhole), dp = mp.distort_pixel(s.pinhole),
                 dm = mm.distort_pixel(s.pinhole);
      if (!d0 || !dp || !dm) continue;
      const Eigen::Vector2d J = (*dp - *dm) / (2.0 * h);
      g += J.dot(*d0 - s.raw);
      jj += J.squaredNorm();
    }
    if (!(jj > 0.0)) break;
    double step = -g / jj;
    bool improved = false;
    for (int ls = 0; ls < 30; ++ls, step *= 0.5) {
      DivisionModel cand = m;
      cand.lambda += step;
      const double c = sum_sq(cand, samples);
      if (c < cost) {
        improved = std::abs(step) > 1e-13 * std::abs(m.lambda) && cost - c > 1e-15 * cost;
        m = cand;
        cost = c;
        break;
      }
    }
    if (!improved) break;
  }
  return division_residuals(cam, m, step_px);
}

}  // namespace naneye::recon
