// The sparse path's nested widening (SparseSettings::wide_step, sparse_wide.cpp): the LK window grows
// ring by ring, each step's match held to the three tests against the step before. A plane goes on
// to the widest window; a curved surface stops where its misfit shows; every window's points keep
// honest sigmas. The single step straight to the widest window (tested against the 9 x 9 one's
// noise) let the sphere's curvature through: on this test's sphere render, 279 of 512 points at
// 21 x 21 with rms(err/sigma) 1.62 (nested: 1 point there, 1.18 at 17 x 17); over bench_scene's
// three renders 25 per pair at 2.14 (--wide-radius 10 --wide-step 6 --refusals, 2026-12-07).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "naneye/recon/scene/sparse.hpp"
#include "scene_fixture.hpp"

namespace naneye::sparse_nested_test {
namespace {

struct WindowFigures {
  int points = 0;  // valid points whose match came from this window
  int good = 0;    // of them, within 5 % of the truth
  double z2 = 0;   // sum of (dZ / sigma)^2 over the good ones
  double rel = 0;  // sum of |dZ| / Z over the good ones
  double rms() const { return std::sqrt(z2 / std::max(1, good)); }
};

// The key of by_window's tally of the points kept after a failed shift test, whatever their window.
constexpr int kDisagreed = -1;
// Good points a window needs before its rms(err/sigma) is held to the band on its own (below).
constexpr int kEnoughPoints = 50;

// Per LK window radius: the valid points of `renders` renders of `preset` (seeds 5, 6, ..); under
// kDisagreed again those whose wider window disagreed (ScenePoint::window_disagreement_px).
std::map<int, WindowFigures> by_window(const std::string& preset, const recon::scene::SparseSettings& s,
                                       std::vector<int>* radii = nullptr, int renders = 1) {
  recon::scene::SparseReconstructor sr(test::paper_d3(), s);
  if (radii) *radii = sr.wide_radii();
  std::map<int, WindowFigures> f;
  for (int k = 0; k < renders; ++k) {
    const sim::TexturedPair& p = test::textured_pair(preset, false, 5 + static_cast<std::uint64_t>(k));
    sr.reset_ids();
    recon::scene::SparseResult out;
    sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), out);
    for (const auto& q : out.points) {
      if (!q.valid()) continue;
      const double zt = p.depth.at<double>(static_cast<int>(std::lround(q.left_px.y())),
                                           static_cast<int>(std::lround(q.left_px.x())));
      for (const int key : {q.window_radius_px, q.window_disagreement_px > 0 ? kDisagreed : 0}) {
        if (key == 0) continue;
        WindowFigures& w = f[key];
        ++w.points;
        if (!(std::abs(q.X.z() - zt) <= 0.05 * zt)) continue;
        ++w.good;
        w.z2 += std::pow((q.X.z() - zt) / q.depth_sigma_mm, 2);
        w.rel += std::abs(q.X.z() - zt) / zt;
      }
    }
  }
  for (const auto& [r, w] : f)
    if (r == kDisagreed)
      std::printf("%-9s windows disagreed  points %3d  rms(err/sigma) %.2f\n", preset.c_str(), w.points,
                  w.rms());
    else
      std::printf("%-9s %2dx%-2d  points %3d  rms(err/sigma) %.2f\n", preset.c_str(), 2 * r + 1, 2 * r + 1,
                  w.points, w.rms());
  return f;
}

recon::scene::SparseSettings ladder(int wide_radius, int step) {
  recon::scene::SparseSettings s;
  s.wide_radius = wide_radius;
  s.wide_step = step;
  return s;
}

TEST(SparseNestedWidening, TheStepsAreTheRingsUpToTheWidest) {
  std::vector<int> radii;
  by_window("plane", ladder(10, 2), &radii);
  EXPECT_EQ(radii, (std::vector<int>{6, 8, 10}));
  by_window("plane", ladder(10, 4), &radii);
  EXPECT_EQ(radii, (std::vector<int>{8, 10}));  // the last ring is narrower, not beyond the cap
  by_window("plane", ladder(6, 2), &radii);
  EXPECT_EQ(radii, (std::vector<int>{6}));  // the default: one step, as before the nesting
  by_window("plane", ladder(0, 2), &radii);
  EXPECT_TRUE(radii.empty());
}

TEST(SparseNestedWidening, APlaneGoesWideTheHeightFieldStopsEarly) {
  const auto plane = by_window("plane", ladder(10, 2));
  const auto height = by_window("height", ladder(10, 2));
  int plane_all = 0, height_all = 0;
  for (const auto& [r, w] : plane) {
    if (r == kDisagreed) continue;
    EXPECT_TRUE(r == 4 || r == 6 || r == 8 || r == 10) << r;
    plane_all += w.points;
  }
  for (const auto& [r, w] : height) height_all += r == kDisagreed ? 0 : w.points;
  ASSERT_GT(plane_all, 400);
  ASSERT_GT(height_all, 400);
  // Measured (3 renders): the plane 69 % of its points at 21 x 21; the height field none beyond
  // 13 x 13 (its 13 x 13 windows 1 %).
  EXPECT_GT(plane.count(10) ? plane.at(10).points : 0, plane_all / 2);
  EXPECT_EQ(height.count(8) + height.count(10), 0u);
}

// rms(err / sigma) within the 0.7-1.4 in every window that holds at least kEnoughPoints
// good points, on the planes and the curved sphere and height field, at the nested widening to
// 17 x 17, over three renders; a preset's window with fewer is pooled with the other presets' of
// the same size. A window of a few dozen points is too few: n points' rms of unit errors has a
// spread of ~1 / sqrt(2 n) (0.15 at 23: the sphere's 13 x 13 windows since the features are tried
// strongest first, rms 0.63, 2.5 spreads below 1; 0.84 on 58 before), and the points a plane
// leaves at 9 x 9 are mostly those along the image's top edge, where the wider windows do not fit,
// with errors alike (seed 5's plane-far: 32 points, 15 on the edge row, rms 0.60 since the
// interpolant's share, 0.72 before; seeds 5-7: 114 points, 0.84). At 50 the spread is 0.10: a
// true 1 falls below 0.7 at 3 spreads.
//
// The points kept after a failed shift test are a selection: on a surface the affine fits, the
// test fails where the narrower match's noise is large, so with its own sigma their rms(err/sigma)
// was 1.6-2.3 (bench_scene --refusals, every condition); their sigma now takes the disagreement
// (sparse_wide.cpp). Too few per preset; pooled over the four: 13 points, rms 0.96 (2.53 with the
// disagreement left out of their sigma; 48 points before the one step first, SparseSettings::
// wide_direct, which leaves fewer narrow matches behind a failed test).
TEST(SparseNestedWidening, EveryWindowsSigmasHold) {
  const auto pool = [](WindowFigures& into, const WindowFigures& w) {
    into.points += w.points;
    into.good += w.good;
    into.z2 += w.z2;
  };
  WindowFigures disagreed;
  std::map<int, WindowFigures> few;  // by radius, the presets' windows of too few points, pooled
  for (const char* preset : {"plane", "plane-far", "sphere", "height"})
    for (const auto& [r, w] : by_window(preset, ladder(8, 2), nullptr, 3)) {
      if (r == kDisagreed) {
        pool(disagreed, w);
        continue;
      }
      if (w.good < kEnoughPoints) {
        pool(few[r], w);
        continue;
      }
      EXPECT_GE(w.rms(), 0.7) << preset << " radius " << r;
      EXPECT_LE(w.rms(), 1.4) << preset << " radius " << r;
    }
  for (const auto& [r, w] : few) {
    std::printf("%2dx%-2d windows of fewer than %d points, pooled: %d points, rms(err/sigma) %.2f\n",
                2 * r + 1, 2 * r + 1, kEnoughPoints, w.good, w.rms());
    if (w.good < kEnoughPoints) continue;
    EXPECT_GE(w.rms(), 0.7) << "pooled radius " << r;
    EXPECT_LE(w.rms(), 1.4) << "pooled radius " << r;
  }
  std::printf("windows disagreed, pooled: %d points, rms(err/sigma) %.2f\n", disagreed.good, disagreed.rms());
  ASSERT_GE(disagreed.good, 10);
  EXPECT_GE(disagreed.rms(), 0.7);
  EXPECT_LE(disagreed.rms(), 1.4);
}

// The reason for the nesting, on the sphere: without the curvature model (curvature_radius_px 0),
// the single step to 21 x 21 keeps windows whose curvature misfit its test (against the 9 x 9
// window's noise) cannot see; step by step, each test against the window just before sees it. With
// the model (sparse_curvature.cpp) the bias is removed from the match itself, so even the single
// step holds (measured 2026-12-07 on this render: 1.01 against 1.6 without it).
TEST(SparseNestedWidening, TheSpheresCurvatureStopsTheNestingNotTheSingleStep) {
  recon::scene::SparseSettings no_model = ladder(10, 6);
  no_model.curvature_radius_px = 0;
  const auto single = by_window("sphere", no_model);
  ASSERT_TRUE(single.count(10));
  ASSERT_GE(single.at(10).good, 10);
  EXPECT_GT(single.at(10).rms(), 1.4);
  no_model.wide_step = 2;
  for (const auto& [r, w] : by_window("sphere", no_model))
    if (w.good >= 10) {
      EXPECT_LE(w.rms(), 1.4) << "radius " << r;
    }
  const auto modelled = by_window("sphere", ladder(10, 6));
  ASSERT_TRUE(modelled.count(10));
  ASSERT_GE(modelled.at(10).good, 100);
  EXPECT_LE(modelled.at(10).rms(), 1.4);
}

// SparseSettings::wide_direct: the one step straight to 21 x 21 first, the ladder only where its
// tests refuse it. The features it refuses still reach 13 x 13 and 17 x 17 (the fallback runs),
// and over the whole render the depth error is no worse than the ladder's for every feature,
// whose three fits it mostly replaces by one (bench_scene --nested-only for the time).
TEST(SparseNestedWidening, OneStepFirstFallsBackToTheLadder) {
  const auto total = [](const std::map<int, WindowFigures>& f) {
    WindowFigures all;
    for (const auto& [r, w] : f) {
      if (r == kDisagreed) continue;
      all.points += w.points;
      all.good += w.good;
      all.rel += w.rel;
    }
    return all;
  };
  recon::scene::SparseSettings nested_only = ladder(10, 2);
  nested_only.wide_direct = false;
  for (const char* preset : {"plane", "sphere"}) {
    const auto direct = by_window(preset, ladder(10, 2), nullptr, 2);
    const auto nested = by_window(preset, nested_only, nullptr, 2);
    const WindowFigures d = total(direct), n = total(nested);
    std::printf("%-7s one step first: %d good, mean |dZ|/Z %.4f %%; ladder only: %d good, %.4f %%\n", preset,
                d.good, 100 * d.rel / d.good, n.good, 100 * n.rel / n.good);
    ASSERT_GT(d.good, 400) << preset;
    EXPECT_GE(d.good, n.good - 5) << preset;
    EXPECT_LE(d.rel / d.good, 1.05 * n.rel / n.good) << preset;
    EXPECT_GT(direct.count(10) ? direct.at(10).points : 0, d.points / 2) << preset;
    EXPECT_GT((direct.count(6) ? direct.at(6).points : 0) + (direct.count(8) ? direct.at(8).points : 0), 10)
        << preset << ": the ladder below the widest";
  }
}

// Matching stops at max_points valid points (counted with the narrow or the widest window's
// precision), but the ladder the one step falls back to can make a few more precise later: the
// result is trimmed after the max_points-th valid point, as if the features after it were never
// tried (without the trim all four renders here had more; bench_scene's plane-far 513-514 per pair).
TEST(SparseNestedWidening, TheFallbackKeepsTheCountAtMaxPoints) {
  recon::scene::SparseReconstructor sr(test::paper_d3());
  const int max_points = sr.settings().max_points;
  for (std::uint64_t seed = 5; seed < 9; ++seed) {
    const sim::TexturedPair& p = test::textured_pair("plane-far", false, seed);
    recon::scene::SparseResult out;
    sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), out);
    int valid = 0;
    for (const auto& q : out.points) valid += q.valid();
    EXPECT_EQ(valid, out.valid_count) << seed;
    EXPECT_LE(out.valid_count, max_points) << seed;
    if (out.valid_count == max_points) {
      EXPECT_TRUE(out.points.back().valid()) << seed << ": the last one kept is the max_points-th valid";
    }
  }
}

TEST(SparseNestedWidening, AStepBelowOnePixelIsRefused) {
  try {
    recon::scene::SparseReconstructor sr(test::paper_d3(), ladder(8, 0));
    ADD_FAILURE() << "made";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wide_step 0 must be at least 1 px"), std::string::npos) << e.what();
  }
}

TEST(SparseNestedWidening, ACurvatureRadiusOutsideTheImageIsRefused) {
  for (const double r : {-1.0, 1e6, std::nan("")}) {
    recon::scene::SparseSettings s;
    s.curvature_radius_px = r;
    try {
      recon::scene::SparseReconstructor sr(test::paper_d3(), s);
      ADD_FAILURE() << "made with " << r;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("curvature_radius_px"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace naneye::sparse_nested_test
