// "Hot paths allocate nothing per frame": DenseReconstructor::reconstruct once warm, mono and Bayer.
// The integer stage is our own SGM (recon/scene/sgm.hpp), its buffers sized at construction: not one
// allocation per pair (until 2026-12-04 cv::StereoSGBM::compute allocated its work buffers on every
// call and the test allowed exactly those).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <utility>

#include "../support/correlated_covariance.hpp"
#include "../support/heap_count.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

TEST(DenseAllocations, NoneOncePairsFlow) {
  test::keep_opencv_on_this_thread();
  // The third case: a calibration with its covariance, so that every depth also gets its
  // calibration sigma (CalibrationSigmaTable, the exact propagation beyond the table's band).
  for (const auto& [bayer, covariance] :
       {std::pair{false, false}, std::pair{true, false}, std::pair{false, true}}) {
    const auto& a = test::textured_pair("plane", bayer);
    const auto& b = test::textured_pair("sphere", bayer);
    recon::StereoRig rig = test::paper_d3();
    if (covariance) rig.sigmas.covariance = test::correlated_covariance(rig, 0.1, 5);
    recon::scene::SparseReconstructor sr(rig);
    recon::scene::DenseReconstructor dr(rig);
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
    EXPECT_EQ(allocations, 0) << (bayer ? "bayer" : "mono") << (covariance ? ", with covariance" : "");
    EXPECT_EQ(std::isfinite(map.calib_sigma_median_mm), covariance);
    EXPECT_GT(valid, 20000);  // the pairs were really reconstructed
  }
}

}  // namespace
}  // namespace naneye
