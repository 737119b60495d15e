// "Hot paths allocate nothing per frame": SparseReconstructor::reconstruct, once warm, on mono and
// Bayer pairs of different scenes (the buffers are sized at construction and by the first pair).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "../support/heap_count.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

TEST(SparseAllocations, NoneOncePairsFlow) {
  test::keep_opencv_on_this_thread();
  for (bool bayer : {false, true}) {
    const auto& a = test::textured_pair("plane", bayer);
    const auto& b = test::textured_pair("tube", bayer);
    recon::scene::SparseReconstructor sr(test::paper_d3());
    recon::scene::SparseResult res;
    sr.reconstruct(sim::raw_view(a.left, bayer), sim::raw_view(a.right, bayer), res);  // warm-up
    const long before = test::heap_allocations();
    int valid = 0;
    for (int i = 0; i < 3; ++i) {
      const auto& p = i % 2 ? a : b;
      sr.reconstruct(sim::raw_view(p.left, bayer), sim::raw_view(p.right, bayer), res);
      valid += res.valid_count;
    }
    EXPECT_EQ(test::heap_allocations() - before, 0) << (bayer ? "bayer" : "mono");
    EXPECT_GT(valid, 900);  // the pairs were really reconstructed
  }
}

}  // namespace
}  // namespace naneye
