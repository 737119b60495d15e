// The dense path against the Cramér-Rao bound of the render (sim/disparity_bound.hpp): its sigma
// may not claim more than the window holds, it gives what the bound allows, and the tube's coverage
// shortfall is the scene's, not the matcher's (docs/scene.md, "What any matcher could give").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <string>
#include <vector>

#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/disparity_bound.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

struct BoundRun {
  std::vector<double> ratio;  // our sigma (as a disparity) over the bound, per depth we give
  long seen = 0, reachable = 0, ours_reachable = 0;
  long seen_far = 0, reachable_far = 0;  // beyond 30 mm
};

// bench_scene's first render of `preset` (mono), its noise-free twin, our dense map against the bound
// at the window the matcher chose.
BoundRun run(const std::string& preset) {
  const auto& rig = test::paper_d3();
  const sim::SensorSettings sensor = test::textured_sensor(false);
  const sim::TexturedRenderer clean_renderer(rig, sim::noise_free_twin(sensor));
  const sim::TexturedPair p = sim::numbered_render(test::textured_renderer(false), preset, 0);
  const sim::TexturedPair c = sim::numbered_render(clean_renderer, preset, 0);
  recon::scene::SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(p.left), sim::raw_view(p.right));
  recon::scene::DenseReconstructor dr(rig);
  recon::scene::DepthMap map;
  dr.reconstruct(sr.luma(), map);
  const cv::Mat bound = sim::disparity_bound(rig, sensor, c.left, p.depth, dr.matcher().radius_used());
  const double max_sigma = dr.settings().matcher.max_sigma_px;
  BoundRun out;
  for (int v = 0; v < p.depth.rows; ++v)
    for (int u = 0; u < p.depth.cols; ++u) {
      const double zt = p.depth.at<double>(v, u), b = bound.at<double>(v, u);
      if (!std::isfinite(zt)) continue;
      const bool reachable = b <= max_sigma, ours = std::isfinite(map.z_at(u, v));
      ++out.seen;
      out.reachable += reachable;
      out.ours_reachable += reachable && ours;
      out.seen_far += zt > 30;
      out.reachable_far += zt > 30 && reachable;
      if (ours && std::isfinite(b)) {
        out.ratio.push_back(
            sim::disparity_sigma(rig, Eigen::Vector2d(u, v), map.z_at(u, v), map.sigma_at(u, v)) / b);
      }
    }
  std::sort(out.ratio.begin(), out.ratio.end());
  return out;
}

double quantile(const std::vector<double>& sorted, double f) {
  return sorted[static_cast<std::size_t>(f * double(sorted.size() - 1))];
}

// No estimator beats the bound; our sigma is itself an estimate from a window's ~45 residual degrees
// of freedom (relative spread ~1 / sqrt(2 nu) ~ 0.1), so a sigma of the right size sits at ~1 with
// its 5 % quantile near 1 - 1.64 x 0.1 (after the floor the lower tail is also the bound's own
// approximations: 0.8 is empirical with that reasoning behind it). Before the floor under the
// window's residual variance (dense_match.cpp) the sphere's was 0.770 (bound without the epipolar
// scale correction; 0.871 after the floor there, 0.847 with it): sigmas low by a quiet window.
TEST(DenseBound, SigmaDoesNotClaimMoreThanTheWindowHolds) {
  const BoundRun r = run("sphere");
  ASSERT_GT(r.ratio.size(), 30000u);
  const double p5 = quantile(r.ratio, 0.05), p50 = quantile(r.ratio, 0.5);
  std::printf("sphere: our sigma / bound p5 %.3f median %.3f; %ld of %ld reachable given (%.1f %%)\n", p5,
              p50, r.ours_reachable, r.reachable, 100.0 * double(r.ours_reachable) / double(r.reachable));
  EXPECT_GT(p5, 0.8);
  EXPECT_GT(p50, 0.95);
  EXPECT_LT(p50, 1.3);  // and not so large that it refuses what it could give
  // It gives what the bound allows: at least 90 % of the reachable pixels (the rest is mostly the
  // edge of what both eyes see, where a window lacks data).
  EXPECT_GT(double(r.ours_reachable), 0.9 * double(r.reachable));
}

// The tube's far part lies in the blur's stop band (its texture sized for 12 mm): beyond 30 mm
// almost no pixel can reach the sigma rule, so no matcher at that rule clears the 80 % on
// the whole tube; ours gives most of what it can. The first two checks hold the scene and the bound
// (what the docs claim of them); only the last can catch a matcher regression.
TEST(DenseBound, TubeBeyondThirtyMillimetresIsOutOfReachOfAnyMatcher) {
  const BoundRun r = run("tube");
  ASSERT_GT(r.seen_far, 5000);
  std::printf("tube: reachable %.1f %% (beyond 30 mm %.1f %%), ours %.1f %% of the reachable\n",
              100.0 * double(r.reachable) / double(r.seen),
              100.0 * double(r.reachable_far) / double(r.seen_far),
              100.0 * double(r.ours_reachable) / double(r.reachable));
  EXPECT_LT(double(r.reachable_far), 0.05 * double(r.seen_far));
  // 75-81.5 % at radius 3-5 (docs/scene.md): at best the 80 %, never clear of it.
  EXPECT_LT(double(r.reachable), 0.85 * double(r.seen));
  EXPECT_GT(double(r.ours_reachable), 0.8 * double(r.reachable));
}

}  // namespace
}  // namespace naneye
