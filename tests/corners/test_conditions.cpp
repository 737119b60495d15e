// The imaging-condition matrix (imaging_conditions.hpp) in the ordinary suite: a few pairs per
// condition, mono and Bayer, against the simulator's truth (bench/bench_conditions.cpp runs more and
// prints the figures, with the OpenCV path beside ours). And the white balance: corners that do not
// depend on the channel gains.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "corner_test_util.hpp"
#include "imaging_conditions.hpp"

namespace naneye::recon {
namespace {

constexpr int kPairsPerCondition = 2;

// Renders kPairsPerCondition pairs of `cond` and detects both eyes: every in-view pair found (when the
// condition expects it), every returned corner where the truth has it.
// By default the pairs' poses come from seed 31 and their noise from 700 + k; a test may take the
// bench's own (bench_conditions: poses 1212, noise 4000 + k) to replay pairs that failed there.
struct PairSource {
  std::uint64_t pose_seed = 31, noise_seed = 700;
  int pairs = kPairsPerCondition;
  // Only these of the first `pairs` (the poses of the others are drawn and skipped); empty: all.
  std::vector<int> only = {};
  // Found in every pair even where the condition does not expect it (pairs known to be found).
  bool expect_found = false;
  // Bounds on the unflagged corners (px): where the truth has them, see check_condition.
  double worst_px = 0.25, rms_px = 0.08;
};

void check_condition(const test::ImagingCondition& cond, const PairSource& src = {}) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector left(rig.left), right(rig.right);
  const sim::Renderer renderer(rig, cond.scene, cond.sensor);
  std::mt19937_64 poses(src.pose_seed);
  int in_view = 0, found = 0;
  double worst = 0, sum2 = 0, worst_flagged = 0;
  int n = 0, flagged = 0;
  const int expected_pairs = src.only.empty() ? src.pairs : static_cast<int>(src.only.size());
  for (int k = 0; k < src.pairs; ++k) {
    const sim::Pose pose = test::condition_pose(cond, rig, poses);
    if (!src.only.empty() && std::find(src.only.begin(), src.only.end(), k) == src.only.end()) continue;
    sim::Rng rng(src.noise_seed + static_cast<std::uint64_t>(k));
    const sim::RenderedPair p = renderer.render(pose, rng);
    if (!p.truth.board_in_view) continue;
    ++in_view;
    for (const bool is_left : {true, false}) {
      CornerDetector& det = is_left ? left : right;
      CornerResult res;
      const bool ok = det.detect_full(sim::raw_view(is_left ? p.left : p.right, cond.sensor.bayer), res);
      if (cond.expect_found || src.expect_found) {
        EXPECT_TRUE(ok) << cond.name << " pair " << k << (is_left ? " left: " : " right: ")
                        << to_string(det.last_failure());
      }
      if (!ok) {
        EXPECT_EQ(res.count, 0) << cond.name;
        continue;
      }
      found += !is_left;
      const auto& truth = is_left ? p.truth.left_px : p.truth.right_px;
      const bool turned = test::best_turn(res, truth);
      for (int i = 0; i < res.count; ++i) {
        const Corner& c = res.corners[static_cast<std::size_t>(i)];
        const double e = (c.px - truth[static_cast<std::size_t>(turned ? res.count - 1 - i : i)]).norm();
        if (c.flags & kCornerFitPoor) {  // marginal, left out downstream: still no false corner
          worst_flagged = std::max(worst_flagged, e);
          ++flagged;
          continue;
        }
        worst = std::max(worst, e);
        sum2 += e * e;
        ++n;
      }
    }
  }
  const double rms = n ? std::sqrt(sum2 / n) : 0.0;
  std::printf("%-48s in view %d, corners %d, RMS %.4f px, worst %.3f px; flagged poor %d, worst %.3f px\n",
              cond.name.c_str(), in_view, n, rms, worst, flagged, worst_flagged);
  // Geometry conditions draw only poses with every inner corner in view.
  if (cond.poses) {
    EXPECT_EQ(in_view, expected_pairs) << cond.name;
  }
  EXPECT_GE(in_view, 1) << cond.name;
  // No false corner: every unflagged corner where the truth has it (OpenCV's path: 0.1-0.4 px RMS),
  // the flagged ones within 0.5 px (bench_conditions' bound for a false corner).
  EXPECT_LE(worst, src.worst_px) << cond.name;
  EXPECT_LE(rms, src.rms_px) << cond.name;
  EXPECT_LE(worst_flagged, 0.5) << cond.name;
}

// The conditions whose name starts with `prefix` (mono and Bayer).
void check_conditions(const std::string& prefix, const PairSource& src = {}) {
  int checked = 0;
  for (const test::ImagingCondition& cond : test::imaging_conditions()) {
    if (cond.name.rfind(prefix, 0) != 0) continue;
    check_condition(cond, src);
    ++checked;
  }
  EXPECT_GE(checked, 1) << prefix;
}

// The index of the condition named `name` in imaging_conditions().
std::size_t condition_index(const std::string& name) {
  const auto conds = test::imaging_conditions();
  for (std::size_t i = 0; i < conds.size(); ++i)
    if (conds[i].name == name) return i;
  ADD_FAILURE() << "no condition " << name;
  return 0;
}

TEST(Conditions, EveryConditionFindsEveryInViewBoardWithoutFalseCorners) {
  for (const test::ImagingCondition& cond : test::imaging_conditions()) {
    if (!cond.poses) check_condition(cond);
  }
}

// Board at 36-50 mm filling the view, exposure set for that range (mono, Bayer).
TEST(Conditions, CloseBoardsAreFound) {
  check_conditions("close: ");
}

// The same close boards at the exposure for 70 mm: whites clipped at ~3x the clip level. On the Bayer
// path both pairs were refused (fit_rejected) while luminance pixels mixing a clipped site took part
// in the fits; corners whose edge midpoints lie beyond the clip are flagged poor.
TEST(Conditions, CloseClippedBoardsAreFound) {
  check_conditions("close at 36-50 mm, exposure for 70 mm");
}

// Boards tilted 45-60 degrees at Dataset 3's distances: the bench's first 4 pairs, of which 0 and 3
// were refused in both eyes (fit_rejected: edges imaged ~45 degrees apart, misfitted by the product of
// erfs, and the next grid line inside the square window).
TEST(Conditions, SteeplyTiltedBoardsAreFound) {
  check_conditions("tilt 45-60", PairSource{1212, 4000, 4});
}

// The bench's first 5 clipped close pairs: in both eyes of pairs 0 and 4 (mono) and of pair 0 (Bayer)
// the saddle map missed one or two X-junctions (its whites, clipped at ~3x full scale, join across the corner
// and split the dark squares apart), and the lattice, needing every corner, found no grid; it now fills
// interior holes by interpolation and the fit decides.
TEST(Conditions, CloseClippedBoardsWithoutASaddleAreFound) {
  check_conditions("close at 36-50 mm, exposure for 70 mm", PairSource{1212, 4000, 5});
}

// Squares of ~4-6 px: not all found yet (nor by OpenCV, which finds none), but never a false corner.
TEST(Conditions, FarBoardsGiveNoFalseCorners) {
  check_conditions("far: ");
}

// Squares of ~5 px (200-260 mm): bench_conditions' pairs (docs/corners.md, "Far boards"). Mono 4 and
// 6, Bayer 1 and 6 were found since session 5 with the X-junction fit, flagged where its window held
// the next lines' blur (0.085 px RMS, worst 0.29 px); mono 0 and 8 and Bayer 0 were refused
// (fit_rejected) until the harmonic fit (corners/sine_fit.hpp), which models the whole window: now
// the ordinary bounds on unflagged corners (over the bench's 12 pairs: 0.037 / 0.033 px RMS, worst
// 0.14 / 0.12 px, mono / Bayer).
TEST(Conditions, FarBoardsAreFound) {
  check_condition(test::imaging_conditions().at(condition_index("far: squares ~5-6 px (200-260 mm), mono")),
                  PairSource{1212, 4000, 9, {0, 4, 6, 8}, true});
  check_condition(test::imaging_conditions().at(condition_index("far: squares ~5-6 px (200-260 mm), Bayer")),
                  PairSource{1212, 4000, 7, {0, 1, 6}, true});
}

// Squares of ~4 px (300-340 mm): no window held an X-junction alone (mono: fit_rejected in every eye)
// and the Bayer luminance's defect test flattened the squares' centres (no_grid in every eye); the
// harmonic fit and the textured defect test find 11 and 9 of the bench's 12 pairs (0.032 / 0.041 px
// RMS, worst 0.13 / 0.19 px). Two of each here.
TEST(Conditions, SmallestSquaresAreFound) {
  check_condition(test::imaging_conditions().at(condition_index("far: squares ~4 px (300-340 mm), mono")),
                  PairSource{1212, 4000, 2, {}, true});
  check_condition(test::imaging_conditions().at(condition_index("far: squares ~4 px (300-340 mm), Bayer")),
                  PairSource{1212, 4000, 3, {1, 2}, true});
}

TEST(Conditions, NoBoardUnderTheRealSensorGivesNothing) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  for (const bool bayer : {false, true}) {
    sim::SceneSettings scene;
    scene.board_present = false;
    const sim::Renderer renderer(rig, scene, test::real_sensor(bayer));
    for (int k = 0; k < 2; ++k) {
      sim::Rng rng(90 + static_cast<std::uint64_t>(k));
      const sim::RenderedPair p = renderer.render(sim::Pose{}, rng);
      CornerResult res;
      EXPECT_FALSE(det.detect_full(sim::raw_view(p.left, bayer), res));
      EXPECT_EQ(res.count, 0);
      EXPECT_EQ(det.last_failure(), CornerFailure::no_grid);
    }
  }
}

// The same view through GRBG sites of very different gains (noise off, so that only the gains
// differ): the frame's own white balance makes the corners the same as with equal gains.
TEST(Conditions, BayerCornersDoNotDependOnTheChannelGains) {
  const StereoRig& rig = test::paper_d3();
  CornerDetector det(rig.left);
  std::mt19937_64 poses(5);
  const sim::Pose pose = test::random_pose(poses);
  auto corners = [&](std::array<double, 3> gains, CornerResult& res) {
    // Noise and fixed-pattern noise off, whites below the clip at the largest gain (1.5 x 500 DN):
    // only the gains differ between the renders (and the rounding to whole DN).
    sim::SensorSettings s = test::real_sensor(true);
    s.noise = false;
    s.column_fpn_dn = s.dsnu_dn = s.prnu = 0.0;
    s.white_dn = 500;
    s.channel_gain = gains;
    const sim::Renderer renderer(rig, sim::SceneSettings{}, s);
    sim::Rng rng(1);
    const sim::RenderedPair p = renderer.render(pose, rng);
    return det.detect_full(sim::raw_view(p.left, true), res);
  };
  CornerResult equal;
  ASSERT_TRUE(corners({1.0, 1.0, 1.0}, equal)) << to_string(det.last_failure());
  for (const auto& g : std::vector<std::array<double, 3>>{
           {1.5, 1.0, 0.5}, {0.5, 1.0, 1.5}, {0.5, 0.7, 1.5}, {1.2, 0.6, 0.9}}) {
    CornerResult res;
    ASSERT_TRUE(corners(g, res)) << g[0] << "/" << g[1] << "/" << g[2] << ": "
                                 << to_string(det.last_failure());
    ASSERT_EQ(res.count, equal.count);
    double worst = 0;
    for (int i = 0; i < res.count; ++i)
      worst = std::max(
          worst, (res.corners[static_cast<std::size_t>(i)].px - equal.corners[static_cast<std::size_t>(i)].px)
                     .norm());
    std::printf(
        "gains %.1f/%.1f/%.1f: worst corner %.4f px from equal gains; balance R %.3f B %.3f Gb %.3f\n", g[0],
        g[1], g[2], worst, det.cfa_balance().gain[1], det.cfa_balance().gain[2], det.cfa_balance().gain[3]);
    EXPECT_LE(worst, 0.01);
    // The balance recovers the gains relative to Gr (the black level is an offset, not a gain).
    EXPECT_NEAR(det.cfa_balance().gain[1], g[0] / g[1], 0.01 * g[0] / g[1]);
    EXPECT_NEAR(det.cfa_balance().gain[2], g[2] / g[1], 0.01 * g[2] / g[1]);
  }
}

// A white-balanced mosaic's clipped sites read (1020 - offset) / gain, under 1020 for a gain above 1:
// blocks of them (zero variance, the heaviest weight) pulled the noise line to the quantisation
// floor (sigma 0.1 DN on the bench's first steep-tilt pair, whose near side clips under the light).
// The Bayer luminance's noise must be the mono one's times the binomial's 6 / 16 in sigma.
TEST(Conditions, BayerNoiseLeavesClippedSitesOut) {
  const StereoRig& rig = test::paper_d3();
  std::vector<double> sigma;
  for (const bool bayer : {false, true}) {
    for (const test::ImagingCondition& cond : test::imaging_conditions()) {
      if (cond.name != std::string("tilt 45-60 degrees at 58-85 mm, ") + (bayer ? "Bayer" : "mono")) continue;
      std::mt19937_64 poses(1212);
      const sim::Pose pose = test::condition_pose(cond, rig, poses);
      sim::Rng rng(4000);
      const sim::RenderedPair p = sim::Renderer(rig, cond.scene, cond.sensor).render(pose, rng);
      CornerDetector det(rig.left);
      CornerResult res;
      det.detect_full(sim::raw_view(p.left, bayer), res);
      sigma.push_back(std::sqrt(det.noise().variance(130.0)) / (bayer ? 6.0 / 16.0 : 1.0));
    }
  }
  ASSERT_EQ(sigma.size(), 2u);
  std::printf("noise at 130 DN: mono %.2f DN, Bayer (in mono units) %.2f DN\n", sigma[0], sigma[1]);
  // The two estimates come from different pixels (the Bayer one from a quarter as many blocks per
  // site): within 30 % of each other (measured before the fix: 6.4 against 0.3).
  EXPECT_NEAR(sigma[1], sigma[0], 0.3 * sigma[0]);
}

}  // namespace
}  // namespace naneye::recon
