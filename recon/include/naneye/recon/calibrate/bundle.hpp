#pragma once
// The calibration bundle's building blocks (calibrate.hpp is the entry point): the state being
// estimated, its free-parameter layout, the residuals and their analytic Jacobian. Public so that
// tests can check the Jacobian against finite differences.
//
// Free parameters, in order: each camera's free intrinsics (fx fy cx cy k1 k2 p1 p2 k3, minus the
// fixed ones), the stereo pose increment (w_s, T), then per view the board pose increment (w_b, t_b).
// Rotations are updated on the left, R <- Rodrigues(w) R, so the Jacobian is taken at w = 0.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "naneye/recon/calibrate/calibrate.hpp"
#include "naneye/recon/camera/camera_model.hpp"

namespace naneye::recon::bundle {

inline constexpr int kIntrinsics = 9;  // fx fy cx cy k1 k2 p1 p2 k3
using Intrinsics = std::array<double, kIntrinsics>;

Intrinsics intrinsics_of(const CameraModel& cam);
// Throws std::invalid_argument for a non-positive focal length (CameraModel's rule).
CameraModel camera_of(const Intrinsics& v, int width, int height);

struct State {
  Intrinsics cam[2]{};
  Eigen::Matrix3d Rs = Eigen::Matrix3d::Identity();  // X_right = Rs X_left + Ts
  Eigen::Vector3d Ts = Eigen::Vector3d::Zero();
  std::vector<Eigen::Matrix3d> Rb;  // board -> left camera, per view
  std::vector<Eigen::Vector3d> tb;
};

// Which intrinsics are free (the same mask for both cameras).
std::array<bool, kIntrinsics> free_mask(const CalibrationSettings& s);

struct Layout {
  std::array<bool, kIntrinsics> free{};
  std::array<int, kIntrinsics> index[2]{};  // column of each intrinsic, -1 when fixed
  int pose = 0;                             // first column of (w_s, T)
  int views = 0;                            // first column of the board poses
  int columns = 0;
};
Layout make_layout(const CalibrationSettings& s, int view_count);

// The residuals (projected - measured, raw pixels), 2 per corner and eye, in view order, left eye
// first. `J` (rows x layout.columns) is filled when non-null.
void evaluate(const State& st, const Layout& layout, std::span<const CalibrationView> views,
              const BoardGeometry& board, int width, int height, Eigen::VectorXd& r, Eigen::MatrixXd* J);

// State + delta (a vector of layout.columns entries).
State apply(const State& st, const Layout& layout, const Eigen::VectorXd& delta);

int residual_count(std::span<const CalibrationView> views);

// The initial guess: cv::calibrateCamera per eye (from settings.initial's intrinsics when given),
// the board poses it found, and the stereo pose as the mean over the views both eyes saw. Empty with
// `error` set when OpenCV fails or an eye or the stereo pose is not constrained.
std::optional<State> initial_state(std::span<const CalibrationView> views, const BoardGeometry& board,
                                   const CalibrationSettings& settings, std::string& error);

}  // namespace naneye::recon::bundle
