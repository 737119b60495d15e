// The dense matcher's window radius chosen per pair (dense_match.hpp, MatcherSettings::max_radius):
// on a render through the real NanEye's blur (1.0 px) it must choose a larger window and cover more
// of the truth than the fixed r = 3, no less accurately; on the simulator's sharp render it must keep
// r = 3 and give the fixed window's result bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "naneye/recon/scene/dense.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

struct Figures {
  int visible = 0, covered = 0, bad5 = 0;
  double coverage() const { return static_cast<double>(covered) / std::max(1, visible); }
  double bad5_share() const { return static_cast<double>(bad5) / std::max(1, covered); }
};

Figures against_truth(const recon::scene::DepthMap& map, const cv::Mat& truth) {
  Figures f;
  for (int r = 0; r < map.height; ++r)
    for (int c = 0; c < map.width; ++c) {
      const double zt = truth.at<double>(r, c);
      if (!std::isfinite(zt)) continue;
      ++f.visible;
      const float z = map.z_at(c, r);
      if (std::isnan(z)) continue;
      ++f.covered;
      f.bad5 += std::abs(z - zt) > 0.05 * zt;
    }
  return f;
}

struct Run {
  Figures f;
  int radius = 0;
  recon::scene::DepthMap map;
  int again_radius = 0;  // the adaptive matcher on the same pair once more: the carried radius
  bool again_same = false;
};

// The same luminance through a fixed r = 3 matcher and through the adaptive one (the defaults).
std::pair<Run, Run> fixed_and_adaptive(const sim::TexturedPair& p) {
  const auto& rig = test::paper_d3();
  recon::scene::SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(p.left, false), sim::raw_view(p.right, false));
  recon::scene::DenseSettings fixed;
  fixed.matcher.max_radius = fixed.matcher.radius;
  std::pair<Run, Run> out;
  recon::scene::DenseReconstructor a(rig, fixed), b(rig);
  a.reconstruct(sr.luma(), out.first.map);
  b.reconstruct(sr.luma(), out.second.map);
  out.first.radius = a.matcher().radius_used();
  out.second.radius = b.matcher().radius_used();
  // The steady state: the next pair starts at the radius chosen and, the scene unchanged, keeps it
  // (and its result) without a second match.
  recon::scene::DepthMap again;
  b.reconstruct(sr.luma(), again);
  out.second.again_radius = b.matcher().radius_used();
  out.second.again_same = true;
  for (std::size_t i = 0; i < again.z_mm.size(); ++i) {
    const float u = again.z_mm[i], v = out.second.map.z_mm[i];
    out.second.again_same = out.second.again_same && (u == v || (std::isnan(u) && std::isnan(v)));
  }
  out.first.f = against_truth(out.first.map, p.depth);
  out.second.f = against_truth(out.second.map, p.depth);
  for (const Run* r : {&out.first, &out.second})
    std::printf("r %d: coverage %.1f %% bad-5 %.2f %%\n", r->radius, 100 * r->f.coverage(),
                100 * r->f.bad5_share());
  return out;
}

TEST(DenseRadius, RealSensorBlurChoosesALargerWindowAndCoversMore) {
  const sim::TexturedRenderer renderer(test::paper_d3(), sim::SensorSettings::measured(false));
  sim::Rng rng(7);
  const sim::TexturedPair p = renderer.render(*sim::textured_preset("sphere"), rng);
  const auto [fixed, adaptive] = fixed_and_adaptive(p);
  EXPECT_EQ(fixed.radius, 3);
  EXPECT_GT(adaptive.radius, 3);
  EXPECT_EQ(adaptive.again_radius, adaptive.radius);
  EXPECT_TRUE(adaptive.again_same);
  // This render: 56.7 % at r = 3, 74.9 % at the r = 6 chosen (the window's cap).
  EXPECT_GE(adaptive.f.coverage(), fixed.f.coverage() + 0.03);
  EXPECT_LE(adaptive.f.bad5_share(), fixed.f.bad5_share() + 0.001);
}

TEST(DenseRadius, SharpRenderKeepsTheWindowAndItsResult) {
  const auto [fixed, adaptive] = fixed_and_adaptive(test::textured_pair("sphere", false));
  EXPECT_EQ(adaptive.radius, 3);
  EXPECT_EQ(adaptive.again_radius, 3);
  ASSERT_EQ(fixed.map.z_mm.size(), adaptive.map.z_mm.size());
  for (std::size_t i = 0; i < fixed.map.z_mm.size(); ++i) {
    const float a = fixed.map.z_mm[i], b = adaptive.map.z_mm[i];
    ASSERT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << i;
  }
}

}  // namespace
}  // namespace naneye
