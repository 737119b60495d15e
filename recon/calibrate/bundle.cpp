#include "naneye/recon/calibrate/bundle.hpp"

#include <stdexcept>

#include "naneye/recon/camera/rig.hpp"

namespace naneye::recon::bundle {

Intrinsics intrinsics_of(const CameraModel& cam) {
  const Distortion& d = cam.distortion();
  return {cam.fx(), cam.fy(), cam.cx(), cam.cy(), d.k1, d.k2, d.p1, d.p2, d.k3};
}

CameraModel camera_of(const Intrinsics& v, int width, int height) {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = v[0];
  K(1, 1) = v[1];
  K(0, 2) = v[2];
  K(1, 2) = v[3];
  return CameraModel(K, Distortion{v[4], v[5], v[6], v[7], v[8]}, width, height);
}

std::array<bool, kIntrinsics> free_mask(const CalibrationSettings& s) {
  return {true, true, true, true, true, true, s.tangential, s.tangential, !s.fix_k3};
}

Layout make_layout(const CalibrationSettings& s, int view_count) {
  Layout l;
  l.free = free_mask(s);
  int c = 0;
  for (int eye = 0; eye < 2; ++eye)
    for (int j = 0; j < kIntrinsics; ++j) l.index[eye][j] = l.free[j] ? c++ : -1;
  l.pose = c;
  l.views = c + 6;
  l.columns = l.views + 6 * view_count;
  return l;
}

int residual_count(std::span<const CalibrationView> views) {
  int n = 0;
  for (const auto& v : views) n += 2 * static_cast<int>(v.left.size() + v.right.size());
  return n;
}

namespace {

// d(pixel)/d(intrinsics) at the normalized point xn (paper Eq. 5-6 differentiated; skew is 0).
Eigen::Matrix<double, 2, kIntrinsics> intrinsic_jacobian(const CameraModel& cam, const Eigen::Vector2d& xn) {
  const double x = xn.x(), y = xn.y(), r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const Eigen::Vector2d xd = cam.distort(xn);
  const double fx = cam.fx(), fy = cam.fy();
  Eigen::Matrix<double, 2, kIntrinsics> J;
  J << xd.x(), 0, 1, 0, fx * x * r2, fx * x * r4, fx * 2 * x * y, fx * (r2 + 2 * x * x), fx * x * r6,  //
      0, xd.y(), 0, 1, fy * y * r2, fy * y * r4, fy * (r2 + 2 * y * y), fy * 2 * x * y, fy * y * r6;
  return J;
}

}  // namespace

void evaluate(const State& st, const Layout& layout, std::span<const CalibrationView> views,
              const BoardGeometry& board, int width, int height, Eigen::VectorXd& r, Eigen::MatrixXd* J) {
  const CameraModel cams[2] = {camera_of(st.cam[0], width, height), camera_of(st.cam[1], width, height)};
  const int n = residual_count(views);
  r.resize(n);
  if (J) J->setZero(n, layout.columns);
  int row = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    const int vc = layout.views + 6 * static_cast<int>(v);
    for (int eye = 0; eye < 2; ++eye) {
      const auto& corners = eye == 0 ? views[v].left : views[v].right;
      for (const BoardCorner& c : corners) {
        const Eigen::Vector3d P = board.corner(c.row, c.col);
        const Eigen::Vector3d RP = st.Rb[v] * P;
        const Eigen::Vector3d Xl = RP + st.tb[v];
        const Eigen::Vector3d X = eye == 0 ? Xl : Eigen::Vector3d(st.Rs * Xl + st.Ts);
        Eigen::Matrix<double, 2, 3> dX;
        r.segment<2>(row) = cams[eye].project(X, dX) - c.px;
        if (J) {
          const Eigen::Matrix<double, 2, kIntrinsics> Ji = intrinsic_jacobian(cams[eye], X.head<2>() / X.z());
          for (int j = 0; j < kIntrinsics; ++j)
            if (layout.index[eye][j] >= 0) J->block<2, 1>(row, layout.index[eye][j]) = Ji.col(j);
          // Left-multiplied increments: d(exp([w]) R P)/dw = -[R P]x at w = 0.
          if (eye == 0) {
            J->block<2, 3>(row, vc) = -dX * skew(RP);
            J->block<2, 3>(row, vc + 3) = dX;
          } else {
            J->block<2, 3>(row, layout.pose) = -dX * skew(st.Rs * Xl);
            J->block<2, 3>(row, layout.pose + 3) = dX;
            J->block<2, 3>(row, vc) = -dX * st.Rs * skew(RP);
            J->block<2, 3>(row, vc + 3) = dX * st.Rs;
          }
        }
        row += 2;
      }
    }
  }
}

State apply(const State& st, const Layout& layout, const Eigen::VectorXd& delta) {
  State out = st;
  for (int eye = 0; eye < 2; ++eye)
    for (int j = 0; j < kIntrinsics; ++j)
      if (layout.index[eye][j] >= 0) out.cam[eye][j] += delta(layout.index[eye][j]);
  out.Rs = rodrigues(Eigen::Vector3d(delta.segment<3>(layout.pose))) * st.Rs;
  out.Ts += delta.segment<3>(layout.pose + 3);
  for (std::size_t v = 0; v < st.Rb.size(); ++v) {
    const int vc = layout.views + 6 * static_cast<int>(v);
    out.Rb[v] = rodrigues(Eigen::Vector3d(delta.segment<3>(vc))) * st.Rb[v];
    out.tb[v] += delta.segment<3>(vc + 3);
  }
  return out;
}

}  // namespace naneye::recon::bundle
