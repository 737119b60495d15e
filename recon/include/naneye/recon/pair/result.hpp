#pragma once
// The result of reconstructing one stereo pair: the object `naneye recon --json` prints and the
// daemon serves at /v1/depth (docs/http-api.md). Preallocated and reused: a result holds at most
// kMaxCorners points so that producing one allocates nothing per frame.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <optional>

namespace naneye::recon {

inline constexpr int kMaxCorners = 64;  // the paper's boards have 6 x 8 = 48 inner corners

struct PointResult {
  int id = 0, row = 0, col = 0;
  bool valid = false;  // false: coordinates below are not to be used (null in JSON)
  Eigen::Vector2d left_px{0, 0}, right_px{0, 0};  // raw pixels, centres at integers
  Eigen::Vector3d xyz_mm{0, 0, 0};                // triangulated (niter2 + refinement), left camera frame
  double depth_sigma_mm = 0;                      // first-order, from the measured corner noise
  // The depth sigma the calibration allows here (geometry/calibration_uncertainty.hpp): common to
  // every corner of the pair; NaN unless valid and the calibration carries its covariance.
  double calib_sigma_mm = std::numeric_limits<double>::quiet_NaN();
  Eigen::Vector3d xyz_board_mm{0, 0, 0};  // the corner on the fitted board
};

struct BoardResult {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // board frame -> left camera frame
  Eigen::Vector3d translation_mm{0, 0, 0};
  Eigen::Vector3d normal{0, 0, 1};  // unit normal of the board plane, left camera frame, towards the camera
  double distance_mm = 0;           // distance of the plane from the left camera centre
  double rms_px = 0;                // raw-pixel reprojection RMS of the pose over both eyes
};

struct MetricsResult {
  double planarity_mm = 0;       // P
  double distance_error_mm = 0;  // D
  double reprojection_px = 0;    // R
};

struct PairResult {
  std::uint64_t pair = 0;
  std::int64_t t_left_ns = 0, t_right_ns = 0;
  bool board_found = false;
  int point_count = 0;
  std::array<PointResult, kMaxCorners> points{};
  std::optional<BoardResult> board;      // empty when the board is not found
  std::optional<MetricsResult> metrics;  // empty when the board is not found
  // Why board_found is false (static strings, null when it is true or unknown): the pair's outcome
  // (StereoReconstructor: to_string(PairOutcome)) and each eye's corner detector's reason
  // (to_string(CornerFailure); "none" for an eye that found the board).
  const char* failure = nullptr;
  const char* failure_left = nullptr;
  const char* failure_right = nullptr;
  // Each eye's reference-pixel check as the source reported it: "passed", "failed" or "not_checked"
  // (static strings; null when the pair did not come from a source, e.g. a parsed result).
  const char* reference_left = nullptr;
  const char* reference_right = nullptr;
};

}  // namespace naneye::recon
