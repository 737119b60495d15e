#pragma once
// Is a stated sigma the spread of the error? A Monte Carlo tally in mrcal's manner: one scene
// rendered with K noise seeds, per pixel the values, their stated sigmas and the truth. Over the
// pixels valid in every seed: rms(spread / sigma) (the noise's part of the error; 1 for an honest
// sigma), rms(err / sigma), the bias the seeds share (their mean's error less what K seeds' noise
// leaves in a mean, over sigma: one the noise itself causes shows here and not in a noise-free
// render), and the distribution of |err / sigma| (its 68.27 % quantile, 1 for a Gaussian; the share
// beyond a tail bound and the rms of the rest). Used by bench_dense_sigma, bench_dense_snr and
// DenseSnr.* (docs/scene.md, "The gradient from the left").
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace naneye::test {

class SeedSpread {
 public:
  SeedSpread(std::size_t pixels, int seeds)
      : seeds_(seeds),
        s1_(pixels),
        s2_(pixels),
        sig2_(pixels),
        e2_(pixels),
        count_(pixels, 0),
        ratio_(pixels * static_cast<std::size_t>(seeds)) {}

  // Seed k's value at pixel i (sigma > 0), against the truth there.
  void add(std::size_t i, int k, double value, double sigma, double truth) {
    if (count_[i] < 0) return;
    const double e = value - truth;
    s1_[i] += value;
    s2_[i] += value * value;
    sig2_[i] += sigma * sigma;
    e2_[i] += e * e / (sigma * sigma);
    ratio_[i * static_cast<std::size_t>(seeds_) + static_cast<std::size_t>(k)] =
        static_cast<float>(std::abs(e) / sigma);
    ++count_[i];
  }
  // Pixel i has no value in some seed: out of every figure for good.
  void drop(std::size_t i) { count_[i] = -1; }
  // Valid in every seed, once all were added.
  bool complete(std::size_t i) const { return count_[i] == seeds_; }
  double mean_sigma2(std::size_t i) const { return sig2_[i] / seeds_; }

  struct Summary {
    int pixels = 0;                   // valid in every seed
    double spread = 0, err = 0;       // rms over pixels, each over the pixel's sigma
    double sigma_median = 0;          // of the pixels' rms sigma
    double p68 = 0;                   // the 68.27 % quantile of |err / sigma| over pixels and seeds
    double tail_share = 0, core = 0;  // beyond `tail`; the rms of the rest
  };
  Summary summary(float tail) const {
    Summary s;
    double spread = 0, err = 0, core2 = 0;
    int tails = 0, core = 0;
    std::vector<float> ratios, sigmas;
    for (std::size_t i = 0; i < count_.size(); ++i) {
      if (!complete(i)) continue;
      for (int k = 0; k < seeds_; ++k) {
        const float q = ratio_[i * static_cast<std::size_t>(seeds_) + static_cast<std::size_t>(k)];
        ratios.push_back(q);
        if (q > tail) {
          ++tails;
        } else {
          core2 += static_cast<double>(q) * q;
          ++core;
        }
      }
      const double mean = s1_[i] / seeds_, var = (s2_[i] - seeds_ * mean * mean) / (seeds_ - 1);
      spread += var / mean_sigma2(i);
      err += e2_[i] / seeds_;
      sigmas.push_back(static_cast<float>(std::sqrt(mean_sigma2(i))));
      ++s.pixels;
    }
    const int m = std::max(1, s.pixels);
    s.spread = std::sqrt(spread / m);
    s.err = std::sqrt(err / m);
    s.sigma_median = quantile(sigmas, 0.5);
    s.p68 = quantile(ratios, 0.6827);
    s.tail_share = static_cast<double>(tails) / std::max<std::size_t>(1, ratios.size());
    s.core = std::sqrt(core2 / std::max(1, core));
    return s;
  }
  // The bias needs the truth's value: one per pixel for a constant truth (bench_dense_snr, DenseSnr).
  double bias_over_sigma(double truth) const {
    double bias = 0;
    int m = 0;
    for (std::size_t i = 0; i < count_.size(); ++i) {
      if (!complete(i)) continue;
      const double mean = s1_[i] / seeds_, var = (s2_[i] - seeds_ * mean * mean) / (seeds_ - 1);
      bias += ((mean - truth) * (mean - truth) - var / seeds_) / mean_sigma2(i);
      ++m;
    }
    return std::sqrt(std::max(0.0, bias / std::max(1, m)));
  }

 private:
  static double quantile(std::vector<float>& v, double q) {
    if (v.empty()) return 0.0;
    const auto it = v.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), it, v.end());
    return *it;
  }

  int seeds_;
  std::vector<double> s1_, s2_, sig2_, e2_;
  std::vector<int> count_;  // seeds added per pixel; -1: dropped
  std::vector<float> ratio_;
};

}  // namespace naneye::test
