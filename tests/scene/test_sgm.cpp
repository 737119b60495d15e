// Our semi-global matcher (recon/scene/sgm.hpp), the dense path's integer stage: known integer
// disparities on a synthetic rectified pair (with an occlusion), agreement with cv::StereoSGBM on a
// render of this camera, and its scalar / SSE2 / AVX2 builds giving the same bits.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "../../recon/scene/dense_rectify.hpp"
#include "../../recon/scene/sgm.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/textured.hpp"
#include "scene_fixture.hpp"

namespace naneye::recon::scene {
namespace {

// Band-limited random texture along a row coordinate u (sum of sines of 2-12 px wavelengths with
// random phases per row): a scene point seen by both eyes has the same brightness in both.
struct Texture {
  std::vector<double> k, phase, amp;
  explicit Texture(std::uint32_t seed, int rows) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> wl(2.0, 12.0), ph(0, 2 * M_PI), a(0.3, 1.0);
    for (int i = 0; i < 8 * rows; ++i) {
      k.push_back(2 * M_PI / wl(rng));
      phase.push_back(ph(rng));
      amp.push_back(a(rng));
    }
  }
  // Row y mixes its own eight sines and its neighbours' (texture varies smoothly across rows too).
  float at(double u, int y) const {
    double v = 100;
    for (int i = 0; i < 8; ++i) v += 20 * amp[8 * y + i] * std::sin(k[8 * y + i] * u + phase[8 * y + i]);
    return static_cast<float>(v);
  }
};

constexpr int kW = 220, kH = 60;

// A background at disparity 10 with a foreground strip, left columns [150, 190), at disparity 30:
// the right eye sees the strip over [120, 160), and the background's left columns [130, 150) are
// hidden from it.
struct Occlusion {
  cv::Mat left = cv::Mat(kH, kW, CV_32FC1), right = cv::Mat(kH, kW, CV_32FC1);
  explicit Occlusion(std::uint32_t seed) {
    const Texture bg(seed, kH), fg(seed + 1, kH);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const bool strip_l = x >= 150 && x < 190, strip_r = x >= 120 && x < 160;
        left.at<float>(y, x) = strip_l ? fg.at(x, y) : bg.at(x, y);
        right.at<float>(y, x) = strip_r ? fg.at(x + 30, y) : bg.at(x + 10, y);
      }
  }
  static int truth(int x) { return x >= 150 && x < 190 ? 30 : 10; }
  static bool hidden(int x) { return x >= 130 && x < 150; }
};

SgmSettings occlusion_settings() {
  SgmSettings s;
  s.min_disparity = 4;
  s.num_disparities = 32;
  s.lr_max_diff = 1;  // the dense matcher's default (lr_tolerance_px 2)
  return s;
}

TEST(Sgm, FindsKnownIntegerDisparitiesAndRefusesTheOccluded) {
  const Occlusion pair(7);
  const SgmSettings s = occlusion_settings();
  std::vector<int> lo(kH, 0), hi(kH, kW);
  Sgm sgm(kW, kH, s);
  cv::Mat disp(kH, kW, CV_32FC1);
  sgm.run(pair.left, pair.right, lo.data(), hi.data(), disp);
  int seen = 0, right = 0, hidden = 0, refused_hidden = 0;
  for (int y = 3; y < kH - 3; ++y)  // the census and its block reach 3 rows
    for (int x = 0; x < kW; ++x) {
      const float d = disp.at<float>(y, x);
      if (x < sgm.first_column()) {
        EXPECT_TRUE(std::isnan(d)) << x;  // the band leaves the right image there
        continue;
      }
      // Away from the strip's edges (the 3 x 3 block of 5 x 5 windows straddles them).
      const bool near_edge = std::abs(x - 150) < 4 || std::abs(x - 190) < 4 || std::abs(x - 130) < 4;
      if (near_edge) continue;
      if (Occlusion::hidden(x)) {
        ++hidden;
        refused_hidden += std::isnan(d);
        continue;
      }
      ++seen;
      right += std::isfinite(d) && std::lround(d) == Occlusion::truth(x);
    }
  std::printf("known disparities: %d of %d right; hidden background refused: %d of %d\n", right, seen,
              refused_hidden, hidden);
  EXPECT_GE(right, 0.98 * seen);
  EXPECT_GE(refused_hidden, 0.5 * hidden);
}

TEST(Sgm, WorksOnlyInsideTheSpans) {
  const Occlusion pair(11);
  Sgm sgm(kW, kH, occlusion_settings());
  std::vector<int> lo(kH), hi(kH);
  for (int y = 0; y < kH; ++y) {
    lo[static_cast<std::size_t>(y)] = 40 + y;
    hi[static_cast<std::size_t>(y)] = y % 9 == 4 ? 0 : 200 - y;  // some rows without data
  }
  cv::Mat disp(kH, kW, CV_32FC1);
  sgm.run(pair.left, pair.right, lo.data(), hi.data(), disp);
  int inside = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool in = x >= lo[static_cast<std::size_t>(y)] && x < hi[static_cast<std::size_t>(y)] &&
                      x >= sgm.first_column();
      if (!in) {
        ASSERT_TRUE(std::isnan(disp.at<float>(y, x))) << x << ", " << y;
      } else {
        inside += std::isfinite(disp.at<float>(y, x));
      }
    }
  EXPECT_GT(inside, 4000);
}

// A band narrowed to the background's disparities (4 .. 19 of 4 .. 35): the background is found as
// in the whole band, no disparity lies outside the band, and the whole band set again gives a fresh
// matcher's bits (the path buffers' pads laid out again). The strip (30 px), outside the band, is
// refused on the band's edge only in part: the SGM gives most of it some disparity in the band (its
// cost has no right answer there), which the dense matcher's own tests must refuse (DenseBand.*).
TEST(Sgm, ANarrowedBandKeepsItsSurfacesAndRefusesItsEdges) {
  const Occlusion pair(7);
  std::vector<int> lo(kH, 0), hi(kH, kW);
  Sgm sgm(kW, kH, occlusion_settings()), fresh(kW, kH, occlusion_settings());
  cv::Mat disp(kH, kW, CV_32FC1), whole(kH, kW, CV_32FC1);
  sgm.set_band(4, 16);
  EXPECT_EQ(sgm.first_column(), 20);
  sgm.run(pair.left, pair.right, lo.data(), hi.data(), disp);
  int seen = 0, right = 0, strip = 0, strip_finite = 0, edge = 0;
  for (int y = 3; y < kH - 3; ++y)
    for (int x = 36; x < kW; ++x) {  // the whole band's first column on: the same pixels as above
      const float d = disp.at<float>(y, x);
      edge += std::isinf(d);
      if (std::isfinite(d)) {
        EXPECT_GE(d, 4.f - 0.5f);
        EXPECT_LE(d, 19.f + 0.5f);
      }
      const bool near_edge = std::abs(x - 150) < 4 || std::abs(x - 190) < 4 || std::abs(x - 130) < 4;
      if (near_edge || Occlusion::hidden(x)) continue;
      if (Occlusion::truth(x) == 30) {
        ++strip;
        strip_finite += std::isfinite(d);
        continue;
      }
      ++seen;
      right += std::isfinite(d) && std::lround(d) == 10;
    }
  std::printf(
      "band 4..19: background %d of %d right; strip (30 px) given a disparity %d of %d; band edge %d "
      "(counted %d)\n",
      right, seen, strip_finite, strip, edge, sgm.band_edge_refused());
  EXPECT_GE(right, 0.98 * seen);
  EXPECT_GT(sgm.band_edge_refused(), 0);
  EXPECT_GE(sgm.band_edge_refused(), edge);  // every refusal counted (some lie left of column 36)
  sgm.set_band(4, 32);
  sgm.run(pair.left, pair.right, lo.data(), hi.data(), disp);
  fresh.run(pair.left, pair.right, lo.data(), hi.data(), whole);
  EXPECT_EQ(std::memcmp(disp.data, whole.data, disp.total() * disp.elemSize()), 0);
  EXPECT_EQ(sgm.band_edge_refused(), 0);
  EXPECT_THROW(sgm.set_band(4, 24), cv::Exception);  // not a multiple of 16
  EXPECT_THROW(sgm.set_band(8, 32), cv::Exception);  // beyond the settings' band
}

// The builds (scalar reference, SSE2, AVX2 where this CPU has it) on the same random spans, images
// with flat patches (equal census bits, ties in S) and a band not starting at 0: the same bits. Every
// band length the path kernel compiles with its length (16-64 px at either width) and one it does
// not (80 px: the general loop).
TEST(SgmKernels, EveryBuildGivesTheScalarBits) {
  std::mt19937 rng(3);
  const int w = 173, h = 41;  // odd sizes
  cv::Mat l(h, w, CV_32FC1), r(h, w, CV_32FC1);
  cv::randu(l, 0, 255);
  const Texture t(5, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      l.at<float>(y, x) = (x / 7 + y / 5) % 5 == 0 ? 50.f : t.at(x, y);
      r.at<float>(y, x) = (x / 7 + y / 5) % 5 == 0 ? 50.f : t.at(x + 9.4, y) + 3.f * (x % 3);
    }
  std::vector<int> lo(h), hi(h);
  std::uniform_int_distribution<int> left(0, w / 2), right(w / 2, w);
  for (int y = 0; y < h; ++y) {
    lo[static_cast<std::size_t>(y)] = left(rng);
    hi[static_cast<std::size_t>(y)] = y % 11 == 5 ? 0 : right(rng);  // some rows without data
  }
  std::vector<sgm_simd::Isa> builds{sgm_simd::Isa::scalar, sgm_simd::Isa::sse2};
  if (sgm_simd::best_isa() == sgm_simd::Isa::avx2) builds.push_back(sgm_simd::Isa::avx2);
  for (const int D : {16, 32, 48, 64, 80}) {
    SCOPED_TRACE(D);
    SgmSettings s;
    s.min_disparity = 3;
    s.num_disparities = D;
    cv::Mat ref(h, w, CV_32FC1), out(h, w, CV_32FC1);
    int ref_refused = 0;
    for (auto isa : builds) {
      Sgm sgm(w, h, s);
      sgm.set_isa(isa);
      sgm.run(l, r, lo.data(), hi.data(), isa == builds.front() ? ref : out);
      if (isa == builds.front()) {
        ref_refused = sgm.left_right_refused();
        EXPECT_GT(cv::countNonZero(ref == ref), 500);  // NaN != NaN: the pixels with a disparity
        continue;
      }
      EXPECT_EQ(sgm.left_right_refused(), ref_refused) << static_cast<int>(isa);
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          const float a = ref.at<float>(y, x), b = out.at<float>(y, x);
          ASSERT_TRUE(std::memcmp(&a, &b, sizeof a) == 0)
              << static_cast<int>(isa) << " at " << x << ", " << y;
        }
    }
  }
}

// Against cv::StereoSGBM as the matcher ran it until 2026-12-04 (3-way, block 5, P1 = 8 x 25,
// P2 = 32 x 25, no uniqueness or speckle filter, its left-right check, 8-bit images on the pair's
// own scale) on an exactly rectified render of this camera: both should find the same integer
// surface where both give a disparity.
TEST(Sgm, AgreesWithStereoSgbmOnARender) {
  const auto& pair = test::textured_pair("sphere", false);
  const StereoRig rig = test::paper_d3();
  SparseReconstructor sr(rig);
  sr.load_luma(sim::raw_view(pair.left, false), sim::raw_view(pair.right, false));
  const StereoLuma& luma = sr.luma();
  const cv::Mat all(luma.height, luma.width, CV_8UC1, cv::Scalar(1));
  const SgmSettings s;  // band 0-47 px: the sphere's 9-20 px inside it
  const RectifiedRig rr = build_rectified_rig(rig, all, all, s.min_disparity + s.num_disparities);
  cv::Mat L(rr.height, rr.width, CV_32FC1), R(rr.height, rr.width, CV_32FC1);
  rr.resample(0, luma.left.data(), luma.width, L);
  rr.resample(1, luma.right.data(), luma.width, R);
  std::vector<int> lo(static_cast<std::size_t>(rr.height), 0), hi(static_cast<std::size_t>(rr.height), 0);
  for (int y = 0; y < rr.height; ++y) {
    int a = 0, b = rr.width;
    while (a < b && !rr.valid[0].at<std::uint8_t>(y, a)) ++a;
    while (b > a && !rr.valid[0].at<std::uint8_t>(y, b - 1)) --b;
    lo[static_cast<std::size_t>(y)] = a;
    hi[static_cast<std::size_t>(y)] = b;
  }
  Sgm sgm(rr.width, rr.height, s);
  cv::Mat ours(rr.height, rr.width, CV_32FC1);
  sgm.run(L, R, lo.data(), hi.data(), ours);

  double top = 0;
  cv::minMaxLoc(cv::max(L, R), nullptr, &top);
  cv::Mat l8, r8, d16;
  L.convertTo(l8, CV_8U, 255.0 / top);
  R.convertTo(r8, CV_8U, 255.0 / top);
  auto sgbm = cv::StereoSGBM::create(s.min_disparity, s.num_disparities, 5, 8 * 25, 32 * 25, 0, 0, 0, 0, 0,
                                     cv::StereoSGBM::MODE_SGBM_3WAY);
  sgbm->compute(l8, r8, d16);
  int both = 0, agree = 0, only_ours = 0, only_sgbm = 0;
  for (int y = 0; y < rr.height; ++y)
    for (int x = 0; x < rr.width; ++x) {
      if (!rr.valid[0].at<std::uint8_t>(y, x) || !rr.valid[1].at<std::uint8_t>(y, x)) continue;
      const float a = ours.at<float>(y, x);
      const short b = d16.at<short>(y, x);
      const bool has_b = b >= s.min_disparity * 16;
      if (std::isfinite(a) && has_b) {
        ++both;
        agree += std::abs(a - b / 16.f) <= 1.f;
      } else {
        only_ours += std::isfinite(a);
        only_sgbm += has_b;
      }
    }
  std::printf("sphere, rectified %d x %d: both %d, within 1 px %d (%.1f %%); only ours %d, only SGBM %d\n",
              rr.width, rr.height, both, agree, 100.0 * agree / std::max(1, both), only_ours, only_sgbm);
  EXPECT_GT(both, 20000);
  EXPECT_GE(agree, 0.97 * both);
}

}  // namespace
}  // namespace naneye::recon::scene
