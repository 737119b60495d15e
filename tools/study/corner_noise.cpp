// The same views with corners as noisy as the paper's must have been: Gaussian noise added to naneye's
// detections. The paper's millimetre P and D are what ~0.2 px corners give through a 1 mm baseline
// (shared/notes/measurements.md: findChessboardCorners + cornerSubPix(3x3) reached 0.15-0.22 px on renders
// of this camera).
#include <random>

#include "naneye/recon/geometry/triangulation.hpp"
#include "study.hpp"

namespace naneye::tools::study {

void reconstruct_polynomial(Dataset& d, double corner_sigma_px) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (View& v : d.views) {
    if (!v.found) continue;
    std::vector<recon::CornerObservation> obs;
    for (std::size_t i = 0; i < v.detected.size(); ++i) {
      v.points[poly_tri][i] = recon::triangulate(d.rig, v.left_px[i], v.right_px[i],
                                                 recon::TriangulationMethod::refined, corner_sigma_px)
                                  .X;
      const int row = static_cast<int>(i) / d.board.cols, col = static_cast<int>(i) % d.board.cols;
      obs.push_back({row, col, v.left_px[i], v.right_px[i], true, true});
    }
    const recon::BoardPose pose = recon::estimate_board_pose(d.rig, d.board, obs, corner_sigma_px);
    for (std::size_t i = 0; i < v.detected.size(); ++i) {
      const int row = static_cast<int>(i) / d.board.cols, col = static_cast<int>(i) % d.board.cols;
      v.points[poly_board][i] =
          pose.ok ? pose.to_camera(d.board.corner(row, col)) : Eigen::Vector3d::Constant(nan);
    }
  }
}

Dataset with_corner_noise(const Dataset& clean, double sigma_px, std::uint64_t seed) {
  Dataset d = clean;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_px);
  for (View& v : d.views) {
    // The OpenCV path has its own corners: it is not part of this experiment.
    v.opencv_found = false;
    if (!v.found) continue;
    for (std::size_t i = 0; i < v.detected.size(); ++i) {
      v.left_px[i] += Eigen::Vector2d(noise(rng), noise(rng));
      v.right_px[i] += Eigen::Vector2d(noise(rng), noise(rng));
    }
  }
  d.opencv_found = 0;
  reconstruct_polynomial(d, sigma_px);
  run_methods(d);
  return d;
}

}  // namespace naneye::tools::study
