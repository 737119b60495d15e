#pragma once
// LDL^T factor and solve of a small symmetric positive-definite matrix of fixed size, the loops
// unrolled by the compiler. Why not Eigen's LDLT: at 6 x 6 it runs its size-generic pivoting code
// through dynamic blocks and triangular-solve kernels; in the affine LK (lk_affine.cpp: three
// factors and a solve per iteration per match) this one took the sparse path from 132.3 M to
// 125.6 M instructions per pair (callgrind, plane mono, 2026-12-05). No pivoting: the matrices here are
// positive definite or refused, and for those LDL^T is stable without it (Golub & Van Loan,
// "Matrix Computations", 4th ed., Sec. 4.1-4.2).
#include <Eigen/Core>

namespace naneye::recon::scene {

template <int N>
class SpdFactor {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;

  // False when a pivot is not > 0 (NaN included): the matrix is not positive definite to working
  // precision, as Eigen's LDLT reports with isPositive() and a zero or negative vectorD().
  bool factor(const Matrix& a) {
    for (int j = 0; j < N; ++j) {
      double d = a(j, j);
      for (int k = 0; k < j; ++k) d -= l_[j][k] * l_[j][k] * d_[k];
      if (!(d > 0)) return false;
      d_[j] = d;
      for (int i = j + 1; i < N; ++i) {
        double x = a(i, j);
        for (int k = 0; k < j; ++k) x -= l_[i][k] * l_[j][k] * d_[k];
        l_[i][j] = x / d;
      }
    }
    return true;
  }

  // A^-1 b, after a successful factor().
  Vector solve(const Vector& b) const {
    double y[N];
    for (int i = 0; i < N; ++i) {
      y[i] = b(i);
      for (int k = 0; k < i; ++k) y[i] -= l_[i][k] * y[k];
    }
    for (int i = 0; i < N; ++i) y[i] /= d_[i];
    Vector x;
    for (int i = N - 1; i >= 0; --i) {
      double v = y[i];
      for (int k = i + 1; k < N; ++k) v -= l_[k][i] * x(k);
      x(i) = v;
    }
    return x;
  }

 private:
  double l_[N][N] = {};  // unit lower triangle, strictly below the diagonal used
  double d_[N] = {};
};

}  // namespace naneye::recon::scene
