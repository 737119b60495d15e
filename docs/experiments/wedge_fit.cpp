// How far is the detector's corner model from a blurred X-junction whose edges are not perpendicular?
// (docs/corners.md, "Close, far and tilted boards".)
//
// A checkerboard near a corner is sign(n1 . u) sign(n2 . u); blurred by a Gaussian of sigma s it is
// E[sign(X1) sign(X2)] with X_k ~ N(n_k . u / s, 1) correlated by rho = n1 . n2, i.e.
// 4 Phi2(m1, m2; rho) - 2 Phi(m1) - 2 Phi(m2) + 1, which is the product of erfs only for rho = 0.
// Renders that exact corner (noise-free, pixel centres, blur 1 px, a window of radius R) for edges
// 90-50 degrees apart, fits the model a + b erf(n1 . (p - q) / sqrt2 s) erf(n2 . (p - q) / sqrt2 s)
// (corner, both normals, blur, a, b; Levenberg-Marquardt, numeric derivatives) and prints the
// corner's error, the fitted blur and the RMS misfit as a share of |b|.
//
//   g++ -O2 -std=c++20 -isystem /usr/include/eigen3 docs/experiments/wedge_fit.cpp -o /tmp/wedge_fit
//
// Session 4 output (R 4 / R 6): misfit 2.0 / 1.5 % at 80 degrees, 3.9 / 2.9 % at 70, 5.7 / 4.4 % at
// 60, 7.0 / 5.9 % at 50; the corner itself within 0.003 px (this symmetric geometry does not bias it).
#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <vector>

namespace {

double Phi(double x) {
  return 0.5 * std::erfc(-x / std::sqrt(2.0));
}
double phi(double x) {
  return std::exp(-0.5 * x * x) / std::sqrt(2.0 * M_PI);
}

// E[sign(X1) sign(X2)] for X ~ N((m1, m2), [[1, r], [r, 1]]): P(X1 > 0, X2 > 0) by quadrature over X1.
double blurred_corner(double m1, double m2, double r) {
  double p = 0;
  const double lo = -m1, hi = 9.0;
  const int n = 2000;
  const double h = (hi - lo) / n;
  for (int i = 0; hi > lo && i < n; ++i) {
    const double z = lo + (i + 0.5) * h;
    p += phi(z) * Phi((m2 + r * z) / std::sqrt(1 - r * r)) * h;
  }
  return 4 * p - 2 * Phi(m1) - 2 * Phi(m2) + 1;
}

}  // namespace

int main() {
  const double s = 1.0, b = 100.0;
  for (const double angle_deg : {90.0, 80.0, 70.0, 60.0, 50.0}) {
    for (const int R : {4, 6}) {
      const double a = angle_deg * M_PI / 180;
      const Eigen::Vector2d n1(1.0, 0.0), n2(std::cos(a), std::sin(a));
      const Eigen::Vector2d c0(0.3, -0.2);  // the corner, off the pixel grid
      std::vector<Eigen::Vector2d> px;
      std::vector<double> val;
      for (int y = -R; y <= R; ++y) {
        for (int x = -R; x <= R; ++x) {
          const Eigen::Vector2d u = Eigen::Vector2d(x, y) - c0;
          px.emplace_back(x, y);
          val.push_back(b * blurred_corner(n1.dot(u) / s, n2.dot(u) / s, n1.dot(n2)));
        }
      }
      auto model = [](const Eigen::VectorXd& q, const Eigen::Vector2d& x) {
        const Eigen::Vector2d m1(std::cos(q[2]), std::sin(q[2])), m2(std::cos(q[3]), std::sin(q[3]));
        const Eigen::Vector2d u = x - Eigen::Vector2d(q[0], q[1]);
        const double k = 1.0 / (std::sqrt(2.0) * q[4]);
        return q[5] + q[6] * std::erf(k * m1.dot(u)) * std::erf(k * m2.dot(u));
      };
      const int n = static_cast<int>(px.size());
      auto cost = [&](const Eigen::VectorXd& q) {
        double c = 0;
        for (int i = 0; i < n; ++i) c += std::pow(model(q, px[i]) - val[i], 2);
        return c;
      };
      Eigen::VectorXd p(7);
      p << c0.x() + 0.05, c0.y() + 0.05, 0.0, a, s, 0.0, b;
      double lambda = 1e-3;
      for (int it = 0; it < 200; ++it) {
        Eigen::MatrixXd J(n, 7);
        Eigen::VectorXd r(n);
        for (int i = 0; i < n; ++i) {
          r[i] = model(p, px[i]) - val[i];
          for (int k = 0; k < 7; ++k) {
            Eigen::VectorXd q = p;
            q[k] += 1e-6;
            J(i, k) = (model(q, px[i]) - model(p, px[i])) / 1e-6;
          }
        }
        Eigen::MatrixXd A = J.transpose() * J;
        A.diagonal() *= 1 + lambda;
        const Eigen::VectorXd d = -A.ldlt().solve(J.transpose() * r);
        if (cost(p + d) < cost(p)) {
          p += d;
          lambda *= 0.3;
        } else {
          lambda *= 10;
        }
      }
      std::printf(
          "edges %.0f deg apart (rho %.2f), R %d: corner off %.3f px, blur %.2f px, misfit %.1f %% of |b|\n",
          angle_deg, n1.dot(n2), R, (Eigen::Vector2d(p[0], p[1]) - c0).norm(), p[4],
          100 * std::sqrt(cost(p) / n) / b);
    }
  }
}
