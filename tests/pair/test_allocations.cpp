// The hot path allocates nothing per pair (issue #6): reconstruct_pair (undistortion, triangulation,
// board pose, P/D/R) and StereoReconstructor::process as a whole on tracked pairs, counted with a
// replaced global operator new over several pairs of a smooth sequence after one warm-up pair. (The
// full search is allocation-free as well: tests/corners/test_search_allocations.cpp.)
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <new>

#include "../corners/corner_test_util.hpp"
#include "../support/heap_count.hpp"
#include "naneye/recon/pair/reconstruction.hpp"
#include "naneye/recon/pair/stereo_reconstructor.hpp"
#include "naneye/sim/sim_source.hpp"

using namespace naneye;

namespace {

// Consecutive pairs of the simulator's smooth "orbit" trajectory at 62 fps, ~70 mm.
std::vector<sim::RenderedPair> smooth_sequence(int pairs) {
  std::vector<sim::RenderedPair> out;
  const sim::BoardGeometry board;
  for (int k = 0; k < pairs; ++k)
    out.push_back(
        test::render(false, sim::trajectory_pose(sim::Motion::orbit, board, 70.0, k / 62.0), 500 + k));
  return out;
}

// The observations StereoReconstructor::process hands to reconstruct_pair.
int observations(const recon::StereoReconstructor& rec,
                 std::array<recon::CornerObservation, recon::kMaxCorners>& obs) {
  const auto& l = rec.left_corners();
  const auto& r = rec.right_corners();
  const int n = std::min(l.count, r.count);
  for (int i = 0; i < n; ++i) {
    const auto& a = l.corners[static_cast<std::size_t>(i)];
    const auto& b = r.corners[static_cast<std::size_t>(i)];
    obs[static_cast<std::size_t>(i)] = {a.row, a.col, a.px, b.px, true, true};
  }
  return n;
}

}  // namespace

TEST(Allocations, ReconstructPairAllocatesNothingPerPair) {
  naneye::test::keep_opencv_on_this_thread();
  const auto seq = smooth_sequence(6);
  recon::StereoReconstructor rec(test::paper_d3(), {});
  recon::PairResult out;
  std::array<recon::CornerObservation, recon::kMaxCorners> obs{};
  int pairs = 0;
  long worst = 0;
  for (std::size_t k = 0; k < seq.size(); ++k) {
    ASSERT_EQ(rec.process(sim::raw_view(seq[k].left, false), sim::raw_view(seq[k].right, false), out),
              recon::PairOutcome::board_found)
        << "pair " << k;
    const int n = observations(rec, obs);
    ASSERT_EQ(n, 48);
    const long before = naneye::test::heap_allocations();
    recon::reconstruct_pair(
        rec.rig(), rec.settings().corners.board, rec.settings().reconstruction,
        std::span<const recon::CornerObservation>(obs.data(), static_cast<std::size_t>(n)), out);
    const long used = naneye::test::heap_allocations() - before;
    ASSERT_TRUE(out.board_found);
    ASSERT_TRUE(out.metrics);
    EXPECT_TRUE(std::isfinite(out.metrics->distance_error_mm));
    EXPECT_TRUE(std::isfinite(out.metrics->planarity_mm));
    if (k == 0) continue;  // warm-up (first use of any lazily built state)
    worst = std::max(worst, used);
    ++pairs;
  }
  EXPECT_EQ(pairs, 5);
  EXPECT_EQ(worst, 0) << "reconstruct_pair allocated per pair";
}

// process() as a whole on a tracked stream: detection (tracking) plus reconstruct_pair.
TEST(Allocations, ProcessAllocatesNothingPerTrackedPair) {
  naneye::test::keep_opencv_on_this_thread();
  const auto seq = smooth_sequence(6);
  recon::StereoReconstructor rec(test::paper_d3(), {});
  recon::PairResult out;
  long total = 0;
  for (std::size_t k = 0; k < seq.size(); ++k) {
    const long before = naneye::test::heap_allocations();
    ASSERT_EQ(rec.process(sim::raw_view(seq[k].left, false), sim::raw_view(seq[k].right, false), out),
              recon::PairOutcome::board_found);
    if (k == 0) continue;
    EXPECT_TRUE(rec.left_corners().tracked && rec.right_corners().tracked) << "pair " << k;
    total += naneye::test::heap_allocations() - before;
  }
  std::printf("StereoReconstructor::process: %.1f heap allocations per tracked pair\n",
              static_cast<double>(total) / static_cast<double>(seq.size() - 1));
  EXPECT_EQ(total, 0);
}
