// The whole per-pair path on the simulator's noisy renders of the paper's Dataset 3 setting: detect,
// triangulate, board pose, P/D/R, against the renders' exact truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../corners/corner_test_util.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"

using namespace naneye;

namespace {

struct RunStats {
  int pairs = 0, in_view = 0, found = 0;
  double tri_sq = 0, board_sq = 0, sigma_sum = 0;
  int n = 0;
  double worst_tri = 0, worst_board = 0, max_p = 0, max_d = 0, max_r = 0;
};

RunStats run(bool bayer, int pairs, std::uint64_t seed) {
  recon::StereoReconstructor rec(test::paper_d3(), {});
  std::mt19937_64 rng(seed);
  RunStats r;
  recon::PairResult out;
  for (int k = 0; k < pairs; ++k) {
    const sim::Pose pose = test::random_pose(rng);
    const auto img = test::render(bayer, pose, seed * 100 + k);
    const bool in_view = test::fully_in_view(img.truth.left_px, img.truth.left_imaged) &&
                         test::fully_in_view(img.truth.right_px, img.truth.right_imaged);
    ++r.pairs;
    r.in_view += in_view;
    const auto outcome = rec.process(sim::raw_view(img.left, bayer), sim::raw_view(img.right, bayer), out);
    if (outcome != recon::PairOutcome::board_found) continue;
    ++r.found;
    for (int i = 0; i < out.point_count; ++i) {
      const auto& p = out.points[i];
      const Eigen::Vector3d& truth = img.truth.corners_mm[static_cast<std::size_t>(p.id)];
      const double eb = (p.xyz_board_mm - truth).norm();
      r.board_sq += eb * eb;
      r.worst_board = std::max(r.worst_board, eb);
      if (!p.valid) continue;
      const double et = (p.xyz_mm - truth).norm();
      r.tri_sq += et * et;
      r.worst_tri = std::max(r.worst_tri, et);
      r.sigma_sum += p.depth_sigma_mm;
      ++r.n;
    }
    r.max_p = std::max(r.max_p, out.metrics->planarity_mm);
    r.max_d = std::max(r.max_d, out.metrics->distance_error_mm);
    r.max_r = std::max(r.max_r, out.metrics->reprojection_px);
  }
  std::printf(
      "%s: %d pairs, %d in view, %d found; triangulated 3D RMS %.3f mm (worst %.3f, mean depth sigma %.3f), "
      "board-pose 3D RMS %.4f mm (worst %.4f); max P %.3f mm, D %.3f mm, R %.4f px\n",
      bayer ? "bayer" : "mono", r.pairs, r.in_view, r.found, std::sqrt(r.tri_sq / r.n), r.worst_tri,
      r.sigma_sum / r.n, std::sqrt(r.board_sq / r.n), r.worst_board, r.max_p, r.max_d, r.max_r);
  return r;
}

}  // namespace

TEST(StereoReconstructor, Dataset3MonoAgainstTruth) {
  const RunStats r = run(false, 10, 11);
  ASSERT_GE(r.in_view, 8);
  EXPECT_GE(r.found, r.in_view);
  const double tri_rms = std::sqrt(r.tri_sq / r.n), board_rms = std::sqrt(r.board_sq / r.n);
  // Corners at <= 0.05 px give ~1 mm per triangulated corner at 70 mm (Z^2/(fT) sqrt(2) sigma);
  // the board pose does an order of magnitude better.
  EXPECT_LT(tri_rms, 2.5);
  EXPECT_LT(board_rms, tri_rms / 5);
  EXPECT_LT(board_rms, 0.3);
  // The reported sigmas are of the size of the real errors (not ten times off either way).
  EXPECT_GT(r.sigma_sum / r.n, tri_rms / 3);
  EXPECT_LT(r.sigma_sum / r.n, tri_rms * 3);
  EXPECT_LT(r.max_r, 0.1);
}

TEST(StereoReconstructor, Dataset3BayerAgainstTruth) {
  const RunStats r = run(true, 6, 12);
  ASSERT_GE(r.in_view, 4);
  EXPECT_GE(r.found, r.in_view);
  EXPECT_LT(std::sqrt(r.board_sq / r.n), 0.3);
}

TEST(StereoReconstructor, NoBoardNoResult) {
  recon::StereoReconstructor rec(test::paper_d3(), {});
  recon::PairResult out;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const auto img = test::render(false, sim::Pose{}, seed, test::Scene::no_board);
    EXPECT_EQ(rec.process(sim::raw_view(img.left, false), sim::raw_view(img.right, false), out),
              recon::PairOutcome::no_board_left);
    EXPECT_FALSE(out.board_found);
    EXPECT_EQ(out.point_count, 0);
    EXPECT_FALSE(out.metrics);
  }
}
