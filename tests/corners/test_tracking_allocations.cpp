// Tracking allocates nothing per frame (docs/corners.md, "Hot paths allocate nothing"): the global
// operator new of this test binary counts the allocations made while counting is switched on.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "../support/heap_count.hpp"
#include "corner_test_util.hpp"

namespace naneye::recon {
namespace {

TEST(CornerAllocation, TrackedFramesAllocateNothing) {
  naneye::test::keep_opencv_on_this_thread();
  // The counter itself must see allocations, or the test could not fail.
  const long probe_before = naneye::test::heap_allocations();
  auto* probe = new std::vector<int>(16);
  delete probe;
  ASSERT_GE(naneye::test::heap_allocations() - probe_before, 1);

  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 rng(41);
  sim::Pose pose = test::random_pose(rng, 65, 75, 25, 2);
  std::vector<cv::Mat> frames;
  for (int f = 0; f < 6; ++f) {
    frames.push_back(test::render(f % 2 == 1, pose, 700 + static_cast<std::uint64_t>(f)).left);
    pose.t += Eigen::Vector3d(0.1, -0.05, 0.2);
    pose.R = Eigen::AngleAxisd(0.005, Eigen::Vector3d(1, 0.4, 0).normalized()).toRotationMatrix() * pose.R;
  }
  CornerResult a, b;
  ASSERT_TRUE(det.detect_full(sim::raw_view(frames[0], false), a)) << to_string(det.last_failure());
  ASSERT_TRUE(det.detect(sim::raw_view(frames[1], true), &a, b));  // warm-up
  int tracked = 0;
  const long before = naneye::test::heap_allocations();
  for (int f = 2; f < 6; ++f) {
    CornerResult& prev = f % 2 == 0 ? b : a;
    CornerResult& now = f % 2 == 0 ? a : b;
    const bool found = det.detect(sim::raw_view(frames[static_cast<std::size_t>(f)], f % 2 == 1), &prev, now);
    tracked += found && now.tracked;
  }
  const long allocations = naneye::test::heap_allocations() - before;
  EXPECT_EQ(tracked, 4);
  EXPECT_EQ(allocations, 0);
}

}  // namespace
}  // namespace naneye::recon
