// The dense path's disparity band from the pair's sparse points (DenseSettings::band_from_sparse):
// as good as the whole band where the points saw every surface, and no wrong depth where they did
// not (a surface outside the band gets none).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "naneye/recon/scene/dense.hpp"
#include "scene_fixture.hpp"

namespace naneye::dense_band_test {

struct Pixels {
  int truth = 0, given = 0, bad5 = 0;
};

// Given depths against the truth, split by where the truth's disparity (f B / Z, the left fx and
// the baseline: the rectification's rotation moves it by well under the 1 px guard) lies against the
// band [lo, hi]: inside by 1 px, outside by 1 px (pixels within 1 px of an edge are in neither).
struct Split {
  Pixels in, out;
};

Split split(const recon::scene::DepthMap& map, const cv::Mat& truth, const recon::StereoRig& rig, int lo,
            int hi) {
  const double fb = rig.left.fx() * rig.right_center().norm();
  Split s;
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) {
      const double zt = truth.at<double>(r, c);
      if (!std::isfinite(zt)) continue;
      const double d = fb / zt;
      Pixels* p = d >= lo + 1 && d <= hi - 1 ? &s.in : (d < lo - 1 || d > hi + 1) ? &s.out : nullptr;
      if (!p) continue;
      ++p->truth;
      const float z = map.z_at(c, r);
      if (std::isnan(z)) continue;
      ++p->given;
      p->bad5 += std::abs(z - zt) / zt > 0.05;
    }
  return s;
}

// The tube seen from inside spans 10-38 px of disparity. Seeded with its far half's points only,
// the band misses the near walls: those pixels must get no wrong depth (the SGM gives most of them
// some disparity in the band, Sgm.ANarrowedBand*: the sub-pixel step's shift, residual and
// left-right tests refuse them), while the pixels inside the band keep what the whole band gives
// them (bad-5 within the whole path's 1 %).
TEST(DenseBand, ASurfaceTheSeedMissedGetsNoWrongDepth) {
  const auto& rig = test::paper_d3();
  const auto& p = test::textured_pair("tube", false);
  recon::scene::SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(p.left, false), sim::raw_view(p.right, false));
  recon::scene::SparseResult seed;
  sr.reconstruct(sr.luma(), seed);
  std::vector<double> z;
  for (const auto& q : seed.points)
    if (q.valid()) z.push_back(q.X.z());
  ASSERT_GT(z.size(), 100u);
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  const double median = z[z.size() / 2];
  recon::scene::SparseResult far = seed;
  far.valid_count = 0;
  for (auto& q : far.points) {
    if (q.valid() && q.X.z() < median) q.status = recon::scene::PointStatus::weak_match;
    far.valid_count += q.valid();
  }

  recon::scene::DenseSettings on;
  on.band_from_sparse = true;
  recon::scene::DenseReconstructor whole(rig, on), narrowed(rig, on), unseeded(rig);
  recon::scene::DepthMap whole_map, map;
  unseeded.reconstruct(sr.luma(), whole_map,
                       &far);         // band_from_sparse off (the default): the seed is ignored
  whole.reconstruct(sr.luma(), map);  // no seed: the whole band
  EXPECT_EQ(whole.matcher().band_size(), whole.matcher().settings().num_disparities);
  EXPECT_EQ(0, std::memcmp(map.z_mm.data(), whole_map.z_mm.data(), map.z_mm.size() * sizeof(float)));

  narrowed.reconstruct(sr.luma(), map, &far);
  const int lo = narrowed.matcher().band_min(), hi = lo + narrowed.matcher().band_size() - 1;
  ASSERT_LT(narrowed.matcher().band_size(), whole.matcher().band_size());
  const Split s = split(map, p.depth, rig, lo, hi), w = split(whole_map, p.depth, rig, lo, hi);
  std::printf(
      "tube, seeded with its far half (%d points): band %d..%d px\n"
      "  truth outside the band: %d px; given %d (whole band %d), off by 5 %%: %d (whole band %d)\n"
      "  truth inside the band:  %d px; given %d (whole band %d), off by 5 %%: %d (whole band %d); band "
      "edge refusals %d\n",
      far.valid_count, lo, hi, s.out.truth, s.out.given, w.out.given, s.out.bad5, w.out.bad5, s.in.truth,
      s.in.given, w.in.given, s.in.bad5, w.in.bad5, narrowed.match_counts().band_edge);
  ASSERT_GT(s.out.truth, 2000);  // the test bites: a real share of the scene lies outside the band
  // Measured: 1 of 7 389 such pixels given a depth (off by 5 %); the whole band gave 1 867 there.
  EXPECT_LE(s.out.bad5, 0.005 * s.out.truth);
  EXPECT_LE(s.in.bad5, 0.01 * std::max(1, s.in.given));
  EXPECT_GE(s.in.given, 0.98 * w.in.given);
}

// Seeded with every point, the band is narrower than the whole one on the scenes whose depth
// range allows it, and on these default renders the map is as good: coverage within 1 point and
// bad-5 no worse (per mille). (Not so on realistic data: DenseBandAloe.)
TEST(DenseBand, TheSeedsBandIsAsGoodAsTheWholeBand) {
  const auto& rig = test::paper_d3();
  for (const char* name : {"plane-far", "sphere", "height"}) {
    const auto& p = test::textured_pair(name, false);
    recon::scene::SparseReconstructor sr(rig);
    sr.load_luma(sim::raw_view(p.left, false), sim::raw_view(p.right, false));
    recon::scene::SparseResult seed;
    sr.reconstruct(sr.luma(), seed);
    recon::scene::DenseSettings on;
    on.band_from_sparse = true;
    recon::scene::DenseReconstructor whole(rig), seeded(rig, on);
    recon::scene::DepthMap wm, sm;
    whole.reconstruct(sr.luma(), wm);
    seeded.reconstruct(sr.luma(), sm, &seed);
    const int lo = 0, hi = 1000;  // every pixel "inside": the whole map's figures
    const Split w = split(wm, p.depth, rig, lo, hi), s = split(sm, p.depth, rig, lo, hi);
    std::printf("%-9s band %d+%d (whole %d+%d): given %d (whole %d) of %d, off by 5 %% %d (whole %d)\n", name,
                seeded.matcher().band_min(), seeded.matcher().band_size(), whole.matcher().band_min(),
                whole.matcher().band_size(), s.in.given, w.in.given, s.in.truth, s.in.bad5, w.in.bad5);
    EXPECT_LT(seeded.matcher().band_size(), whole.matcher().band_size()) << name;
    EXPECT_GE(s.in.given, w.in.given - 0.01 * w.in.truth) << name;
    EXPECT_LE(s.in.bad5, w.in.bad5 + 0.001 * s.in.given) << name;
  }
}

}  // namespace naneye::dense_band_test
