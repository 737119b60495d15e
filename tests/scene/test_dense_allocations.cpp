// "Hot paths allocate nothing per frame": DenseReconstructor::reconstruct once warm, mono and Bayer.
// The integer stage is our own SGM (recon/scene/sgm.hpp), its buffers sized at construction: not one
// allocation per pair (until 2026-12-04 cv::StereoSGBM::compute allocated its work buffers on every
// call and the test allowed exactly those).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "../support/heap_count.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

TEST(DenseAllocations, NoneOncePairsFlow) {
  // As the processor runs it (app/src/processor.cpp): OpenCV on the calling thread (its pool's
  // bookkeeping allocates, should any cv:: call on the path use it).
  cv::setNumThreads(1);
  for (bool bayer : {false, true}) {
    const auto& a = test::textured_pair("plane", bayer);
    const auto& b = test::textured_pair("sphere", bayer);
    recon::scene::SparseReconstructor sr(test::paper_d3());
    recon::scene::DenseReconstructor dr(test::paper_d3());
    recon::scene::DepthMap map;
    sr.load_luma(sim::raw_view(a.left, bayer), sim::raw_view(a.right, bayer));
    dr.reconstruct(sr.luma(), map);  // warm-up
    int valid = 0;
    long allocations = 0;
    for (int i = 0; i < 2; ++i) {
      const auto& p = i % 2 ? a : b;
      sr.load_luma(sim::raw_view(p.left, bayer), sim::raw_view(p.right, bayer));
      const long before = test::heap_allocations();
      dr.reconstruct(sr.luma(), map);
      allocations += test::heap_allocations() - before;
      valid += map.valid_count;
    }
    EXPECT_EQ(allocations, 0) << (bayer ? "bayer" : "mono");
    EXPECT_GT(valid, 20000);  // the pairs were really reconstructed
  }
}

}  // namespace
}  // namespace naneye
