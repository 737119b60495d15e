// Does the dense sigma hold as the signal to noise falls? bench_dense_sigma runs the whole camera
// path (rendering, rectification, a curved surface); here the rectified matcher alone
// (RectifiedMatcher, dense_match.hpp) meets a rectified pair made exactly (sim/wave_pair.hpp: one
// constant disparity, a sum of sinusoids), white Gaussian noise of a chosen sigma per eye, and
// optionally shot noise and 10-bit quantisation. What is left of the sigma's error is the matcher's
// own: its window model, its reference field, its noise estimate. The last block sweeps the
// disparity's fraction: a bias that depends on it is the interpolation's (docs/scene.md, "The
// gradient from the left").
//   build/bench/bench_dense_snr [--seeds K]
// Per case: the texture's contrast over the noise (std / sigma_n), the median stated sigma (px),
// rms(spread / sigma) over K noise seeds (the noise's part), rms(misfit / sigma) (the noise-free
// pair's error), rms(err / sigma), the 68.27 % quantile of |err / sigma| (1 for a Gaussian), and
// bias/s: the rms over pixels of the seeds' mean error less what the seeds' noise leaves in a mean,
// over sigma (a bias the noise itself causes, which the noise-free pair does not show).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

#include "../tests/support/seed_spread.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "naneye/sim/wave_pair.hpp"

using namespace naneye;

namespace {

constexpr int kWidth = 200, kHeight = 160;
constexpr double kMean = 300;  // DN; the texture's mean level

// noise_dn: white Gaussian read noise; shot: also Poisson-like noise of variance signal / gain_e_per_dn
// (the measured NanEye's 7.14 e/DN) and the 10-bit sensor's whole DN (quantised).
void run(double blur_px, double contrast, double noise_dn, int seeds, double mean_dn, bool shot,
         double disparity_px) {
  const sim::WaveTexture w = sim::make_wave_texture(blur_px, contrast, 7);
  const cv::Mat left0 = sim::render_waves(w, kWidth, kHeight, mean_dn, 0);
  const cv::Mat right0 = sim::render_waves(w, kWidth, kHeight, mean_dn, disparity_px);
  const cv::Mat valid(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
  recon::scene::RectifiedMatcher matcher(kWidth, kHeight);
  test::SeedSpread tally(static_cast<std::size_t>(kWidth) * kHeight, seeds);
  double misfit2 = 0;
  int misfit_n = 0;
  for (int k = 0; k <= seeds; ++k) {
    cv::Mat left = left0.clone(), right = right0.clone();
    if (k < seeds) {
      cv::Mat nl(kHeight, kWidth, CV_32FC1), nr(kHeight, kWidth, CV_32FC1);
      cv::RNG cvrng(1000 + static_cast<std::uint64_t>(k));
      cvrng.fill(nl, cv::RNG::NORMAL, 0, noise_dn);
      cvrng.fill(nr, cv::RNG::NORMAL, 0, noise_dn);
      if (shot) {
        constexpr double kGain = 1 / 0.14;  // e/DN
        for (cv::Mat* img : {&left, &right}) {
          cv::Mat sh(kHeight, kWidth, CV_32FC1);
          cvrng.fill(sh, cv::RNG::NORMAL, 0, 1);
          for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
              float& v = img->at<float>(y, x);
              v += static_cast<float>(std::sqrt(std::max(0.f, v) / kGain)) * sh.at<float>(y, x);
            }
        }
      }
      left += nl;
      right += nr;
      if (shot)
        for (cv::Mat* img : {&left, &right})
          for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
              float& v = img->at<float>(y, x);
              v = std::clamp(std::round(v), 0.f, 1023.f);
            }
    }
    matcher.match(left, right, valid, valid);
    const cv::Mat& d = matcher.disparity();
    const cv::Mat& s = matcher.sigma();
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * kWidth + x;
        const double di = d.at<float>(y, x), si = s.at<float>(y, x);
        const bool ok = std::isfinite(di) && std::isfinite(si) && si > 0;
        if (k < seeds) {
          if (ok)
            tally.add(i, k, di, si, disparity_px);
          else
            tally.drop(i);
        } else if (ok && tally.complete(i)) {
          misfit2 += (di - disparity_px) * (di - disparity_px) / tally.mean_sigma2(i);
          ++misfit_n;
        }
      }
  }
  const test::SeedSpread::Summary f = tally.summary(4.f);
  std::printf("%6.3f %5.0f %5s %5.2f %6.1f %6.1f %7.1f %2d %6d %8.4f %8.3f %9.3f %8.3f %6.3f %7.3f\n",
              disparity_px, mean_dn, shot ? "shot" : "-", blur_px, contrast, noise_dn, contrast / noise_dn,
              matcher.radius_used(), f.pixels, f.sigma_median, f.spread,
              std::sqrt(misfit2 / std::max(1, misfit_n)), f.err, f.p68, tally.bias_over_sigma(disparity_px));
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 6;
  for (int a = 1; a + 1 < argc; ++a)
    if (std::strcmp(argv[a], "--seeds") == 0) seeds = std::max(2, std::atoi(argv[a + 1]));
  std::printf("%d noise seeds per case; a %d x %d rectified pair\n", seeds, kWidth, kHeight);
  std::printf("%6s %5s %5s %5s %6s %6s %7s %2s %6s %8s %8s %9s %8s %6s %7s\n", "d px", "mean", "shot", "blur",
              "std", "noise", "std/n", "r", "pixels", "sigma px", "spread/s", "misfit/s", "err/s", "p68",
              "bias/s");
  for (double blur : {0.4, 1.0})
    for (double noise : {1.0, 3.0, 6.0, 10.0, 15.0}) run(blur, 30.0, noise, seeds, kMean, false, 12.37);
  for (double mean : {300.0, 100.0, 40.0})
    for (double c : {30.0, 10.0}) run(1.0, c, 2.5, seeds, mean, true, 12.37);
  for (double frac = 0; frac < 1; frac += 0.125) run(1.0, 30.0, 10.0, seeds, kMean, false, 12 + frac);
  return 0;
}
