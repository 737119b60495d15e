// The daemon runs the full search on every frame without a board, at 62 fps: after the first frame
// the detector must not touch the heap. Counted with a replaced global operator new in this binary
// (Eigen's own dynamic matrices use malloc and are not counted; the detector uses only fixed-size
// Eigen types).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

#include "../support/heap_count.hpp"
#include "corner_test_util.hpp"

namespace naneye::recon {
namespace {

struct Frame {
  cv::Mat image;
  bool bayer;
  bool board_in_view;
};

TEST(CornerAllocation, FullSearchAllocatesNothingAfterTheFirstFrame) {
  naneye::test::keep_opencv_on_this_thread();
  const StereoRig& rig = test::paper_d3();
  std::mt19937_64 rng(31);
  std::vector<Frame> frames;
  for (int k = 0; k < 4; ++k) {  // boards in view, mono and Bayer
    const bool bayer = k % 2 == 1;
    const sim::RenderedPair p =
        test::render(bayer, test::random_pose(rng), 700 + static_cast<std::uint64_t>(k));
    frames.push_back({p.left, bayer, test::fully_in_view(p.truth.left_px, p.truth.left_imaged)});
  }
  for (int k = 0; k < 2; ++k) {  // no board
    const bool bayer = k % 2 == 1;
    frames.push_back(
        {test::render(bayer, sim::Pose{}, 710 + static_cast<std::uint64_t>(k), test::Scene::no_board).left,
         bayer, false});
  }
  sim::Pose cut = test::random_pose(rng, 58, 85, 30, 0);  // a board cut by the image edge
  cut.t += Eigen::Vector3d(0.6 * cut.t.z(), 0.0, 0.0);
  frames.push_back({test::render(false, cut, 720).left, false, false});
  frames.push_back(
      {test::render(false, test::random_pose(rng), 730, test::Scene::small_board).left, false, false});

  CornerDetector det(rig.left);
  CornerResult res, tracked;
  // The first frame may size what it needs.
  det.detect_full(sim::raw_view(frames[0].image, frames[0].bayer), res);
  int found = 0, expected = 0, tracked_ok = 0;
  const long before = naneye::test::heap_allocations();
  for (int round = 0; round < 2; ++round) {
    for (const Frame& f : frames) {
      const bool ok = det.detect_full(sim::raw_view(f.image, f.bayer), res);
      found += ok;
      expected += f.board_in_view;
      if (ok) tracked_ok += det.detect(sim::raw_view(f.image, f.bayer), &res, tracked) && tracked.tracked;
    }
  }
  const long allocations = naneye::test::heap_allocations() - before;
  std::printf("%zu frames x 2: %d boards found (%d in view), %d tracked, %ld heap allocations\n",
              frames.size(), found, expected, tracked_ok, allocations);
  EXPECT_EQ(found, expected);
  EXPECT_EQ(tracked_ok, found);
  EXPECT_EQ(allocations, 0);
}

// The counter does see what the old full search did: OpenCV's findChessboardCorners (the opt-in
// fallback) allocates on every frame without a board.
TEST(CornerAllocation, CounterSeesTheOpenCVFallback) {
  CornerSettings s;
  s.opencv_fallback = true;
  CornerDetector det(test::paper_d3().left, s);
  const cv::Mat empty = test::render(false, sim::Pose{}, 740, test::Scene::no_board).left;
  CornerResult res;
  det.detect_full(sim::raw_view(empty, false), res);
  const long before = naneye::test::heap_allocations();
  EXPECT_FALSE(det.detect_full(sim::raw_view(empty, false), res));
  EXPECT_GT(naneye::test::heap_allocations() - before, 0);
}

}  // namespace
}  // namespace naneye::recon
