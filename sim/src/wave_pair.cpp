#include "naneye/sim/wave_pair.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace naneye::sim {

WaveTexture make_wave_texture(double blur_px, double contrast_dn, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n01(0, 1);
  constexpr double kPi = std::numbers::pi;
  WaveTexture t;
  t.waves.resize(300);
  double var = 0;
  for (WaveTexture::Wave& k : t.waves) {
    const double f = 0.35 * std::sqrt(u(rng)), th = 2 * kPi * u(rng);
    k.fx = f * std::cos(th);
    k.fy = f * std::sin(th);
    k.amp = n01(rng) * std::exp(-2 * kPi * kPi * f * f * blur_px * blur_px);
    k.phase = 2 * kPi * u(rng);
    var += k.amp * k.amp / 2;
  }
  for (WaveTexture::Wave& k : t.waves) k.amp *= contrast_dn / std::sqrt(var);
  return t;
}

cv::Mat render_waves(const WaveTexture& t, int width, int height, double mean_dn, double shift_px) {
  cv::Mat m(height, width, CV_32FC1);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      double v = mean_dn;
      for (const WaveTexture::Wave& k : t.waves)
        v += k.amp * std::cos(2 * std::numbers::pi * (k.fx * (x + shift_px) + k.fy * y) + k.phase);
      m.at<float>(y, x) = static_cast<float>(v);
    }
  return m;
}

}  // namespace naneye::sim
