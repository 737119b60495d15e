// The coarse search's ambiguity (match_along_curve, epipolar_match.hpp): the second best is another
// peak along the curve, not the best one's own shoulder. A blurred texture has a wide correlation
// lobe, and a texture that repeats along the curve has two peaks: only the second is ambiguous.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

#include "naneye/recon/scene/epipolar_match.hpp"

namespace naneye::recon::scene {
namespace {

constexpr int kW = 120, kH = 40, kRadius = 3;

// A horizontal "curve": samples one pixel apart along row 20, columns 20..99.
EpipolarCurve row_curve() {
  EpipolarCurve c;
  for (int x = 20; x < 100; ++x, ++c.n) {
    c.px[static_cast<std::size_t>(c.n)] = Eigen::Vector2d(x, 20);
    c.w[static_cast<std::size_t>(c.n)] = 0.01 * c.n;
    c.inside[static_cast<std::size_t>(c.n)] = true;
  }
  return c;
}

// ZNCC of src's window at (u, 20) against dst's at (x, 20).
double zncc(const cv::Mat& src, const cv::Mat& dst, int u, int x) {
  double mt = 0, md = 0;
  const int n = (2 * kRadius + 1) * (2 * kRadius + 1);
  for (int dr = -kRadius; dr <= kRadius; ++dr)
    for (int dc = -kRadius; dc <= kRadius; ++dc) {
      mt += src.at<float>(20 + dr, u + dc);
      md += dst.at<float>(20 + dr, x + dc);
    }
  mt /= n;
  md /= n;
  double st = 0, ss = 0, sd = 0;
  for (int dr = -kRadius; dr <= kRadius; ++dr)
    for (int dc = -kRadius; dc <= kRadius; ++dc) {
      const double a = src.at<float>(20 + dr, u + dc) - mt, b = dst.at<float>(20 + dr, x + dc) - md;
      st += a * b;
      ss += a * a;
      sd += b * b;
    }
  return st / std::sqrt(ss * sd);
}

// SparseSettings::max_ambiguity's rule.
bool ambiguous(double best, double second) {
  return (1 - best) > 0.5 * (1 - second);
}

// The same texture seen twice with independent noise (sd `noise` DN).
void pair_of(const cv::Mat& texture, float noise, std::mt19937& rng, cv::Mat& a, cv::Mat& b) {
  std::normal_distribution<float> g(0, noise);
  a = texture.clone();
  b = texture.clone();
  for (int r = 0; r < kH; ++r)
    for (int c = 0; c < kW; ++c) {
      a.at<float>(r, c) += g(rng);
      b.at<float>(r, c) += g(rng);
    }
}

TEST(CurveAmbiguity, ABlurredTexturesOwnShoulderIsNoSecondMatch) {
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0, 1);
  const std::vector<std::uint8_t> usable(static_cast<std::size_t>(kW) * kH, 1);
  const EpipolarCurve curve = row_curve();
  // Matches each rule lets through, right (within the LK's reach of the truth, LkSettings::
  // max_travel_px = 2.5 px: the refinement recovers them) and wrong.
  int old_right = 0, old_wrong = 0, lobe_right = 0, lobe_wrong = 0, tried = 0;
  for (int k = 0; k < 10; ++k) {
    cv::Mat white(kH, kW, CV_32FC1), texture, a, b;
    for (int r = 0; r < kH; ++r)
      for (int c = 0; c < kW; ++c) white.at<float>(r, c) = g(rng);
    // A faint, smooth texture (a real NanEye's blur, 1.0-1.6 px, on texture of its own scale): ~9
    // DN of texture against 1.5 DN of noise per image; the correlation lobe spans ~4 samples.
    cv::GaussianBlur(white, texture, cv::Size(0, 0), 3.0);
    texture = texture * 100 + 300;
    pair_of(texture, 1.5f, rng, a, b);
    const GrayView va{a.ptr<float>(), kW, kH}, vb{b.ptr<float>(), kW, kH};
    for (int u = 30; u < 90; u += 4, ++tried) {
      const CurveMatch m = match_along_curve(va, u, 20, vb, usable.data(), curve, kRadius);
      const int best = static_cast<int>(std::lround(m.index));
      const bool right = std::abs(m.index - (u - 20)) < 2.5;
      // What a fixed two-sample exclusion took for the second best: at least the lobe's shoulder.
      const double shoulder = std::max(best >= 2 ? zncc(a, b, u, 20 + best - 2) : -1.0,
                                       best + 2 < curve.n ? zncc(a, b, u, 20 + best + 2) : -1.0);
      if (!ambiguous(m.best, std::max(m.second, shoulder))) ++(right ? old_right : old_wrong);
      if (!ambiguous(m.best, m.second)) ++(right ? lobe_right : lobe_wrong);
    }
  }
  std::printf(
      "blurred faint texture, %d windows: matches let through right / wrong: another peak %d / %d, "
      "a two-sample shoulder %d / %d\n",
      tried, lobe_right, lobe_wrong, old_right, old_wrong);
  EXPECT_EQ(lobe_wrong, 0);                       // never a wrong match let through
  EXPECT_GE(lobe_right, old_right + tried / 10);  // and more of the right ones
}

TEST(CurveAmbiguity, ATextureRepeatingAlongTheCurveIsAmbiguous) {
  std::mt19937 rng(3);
  cv::Mat texture(kH, kW, CV_32FC1), a, b;
  // Period 9 px along the curve, a little structure across it.
  for (int r = 0; r < kH; ++r)
    for (int c = 0; c < kW; ++c)
      texture.at<float>(r, c) =
          static_cast<float>(300 + 80 * std::sin(2 * M_PI * c / 9.0) + 20 * std::sin(r * 0.7));
  pair_of(texture, 4.0f, rng, a, b);
  const GrayView va{a.ptr<float>(), kW, kH}, vb{b.ptr<float>(), kW, kH};
  const std::vector<std::uint8_t> usable(static_cast<std::size_t>(kW) * kH, 1);
  for (int u = 40; u < 80; u += 5) {
    const CurveMatch m = match_along_curve(va, u, 20, vb, usable.data(), row_curve(), kRadius);
    EXPECT_GT(m.second, 0.9) << u;  // the next period
    EXPECT_TRUE(ambiguous(m.best, m.second)) << u;
  }
}

}  // namespace
}  // namespace naneye::recon::scene
