// Never a false corner: frames without a board, boards cut by the image edge, a board of another size.
#include <gtest/gtest.h>

#include <cstdio>

#include "corner_test_util.hpp"

namespace naneye::recon {
namespace {

TEST(CornerNegative, NoBoardNothingFound) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  for (int k = 0; k < 2; ++k) {
    const bool bayer = k % 2 == 1;
    const sim::RenderedPair p =
        test::render(bayer, sim::Pose{}, 100 + static_cast<std::uint64_t>(k), test::Scene::no_board);
    CornerResult res;
    EXPECT_FALSE(det.detect_full(sim::raw_view(p.left, bayer), res));
    EXPECT_EQ(res.count, 0);
  }
}

// Boards shifted sideways so that part of the inner grid leaves the image: either not found, or every
// corner returned is where the truth puts it.
TEST(CornerNegative, BoardCutByEdgeGivesNoFalseCorner) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 rng(77);
  int cut = 0, found = 0, false_corners = 0;
  const double kPi = 3.14159265358979323846;
  for (int k = 0; k < 6; ++k) {
    sim::Pose pose = test::random_pose(rng, 58, 85, 30, 0);
    // Shift the grid centre towards one side by 50-70 % of the distance (the image spans ~ +-0.7).
    const double dir = 2 * kPi * k / 6 + 0.3;
    const double shift = (0.50 + 0.10 * (k % 3)) * pose.t.z();
    pose.t += Eigen::Vector3d(std::cos(dir) * shift, std::sin(dir) * shift, 0);
    const bool bayer = k % 2 == 1;
    const sim::RenderedPair p = test::render(bayer, pose, 200 + static_cast<std::uint64_t>(k));
    if (test::fully_in_view(p.truth.left_px, p.truth.left_imaged, 0.0)) continue;
    ++cut;
    CornerResult res;
    if (!det.detect_full(sim::raw_view(p.left, bayer), res)) continue;
    ++found;
    if (test::max_error(res, p.truth.left_px, test::best_turn(res, p.truth.left_px)) > 0.5) ++false_corners;
  }
  std::printf("cut boards: %d, found anyway: %d, with a false corner: %d\n", cut, found, false_corners);
  EXPECT_GE(cut, 5);
  EXPECT_EQ(found, 0);
  EXPECT_EQ(false_corners, 0);
}

// A board of another size (8 x 6 squares: 7 x 5 inner corners) is not taken for the 9 x 7 board.
TEST(CornerNegative, SmallerBoardNotFound) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 rng(9);
  for (int k = 0; k < 2; ++k) {
    const sim::Pose pose = test::random_pose(rng);
    const sim::RenderedPair p =
        test::render(false, pose, 300 + static_cast<std::uint64_t>(k), test::Scene::small_board);
    CornerResult res;
    EXPECT_FALSE(det.detect_full(sim::raw_view(p.left, false), res)) << "pose " << k;
  }
}

}  // namespace
}  // namespace naneye::recon
