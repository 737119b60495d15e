// Shi-Tomasi features spread over the image by a grid (features.hpp).
#include "naneye/recon/scene/features.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace naneye::recon::scene {

double estimate_noise_sigma(const GrayView& img, const std::uint8_t* mask, const std::array<float, 9>& k) {
  const int w = img.width, h = img.height;
  double sum = 0;
  long n = 0;
  for (int r = 1; r + 1 < h; ++r)
    for (int c = 1; c + 1 < w; ++c) {
      if (mask && !mask[r * w + c]) continue;
      const double v = img.at(c - 1, r - 1) - 2 * img.at(c, r - 1) + img.at(c + 1, r - 1) -
                       2 * img.at(c - 1, r) + 4 * img.at(c, r) - 2 * img.at(c + 1, r) + img.at(c - 1, r + 1) -
                       2 * img.at(c, r + 1) + img.at(c + 1, r + 1);
      sum += std::abs(v);
      ++n;
    }
  if (n == 0) return 0;
  // Immerkaer Eq. 6: sigma = sqrt(pi / 2) / 6 * mean |I * N| for white noise (the mask's L2 norm is
  // 6); for noise filtered by k, |N * k| in place of 6 and |k| the pixel's share (features.hpp).
  constexpr int kMask[9] = {1, -2, 1, -2, 4, -2, 1, -2, 1};
  double nk2 = 0, k2 = 0;
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) {
      double v = 0;  // (N * k) at (r, c) of its 5 x 5 support
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const int a = r - i, b = c - j;
          if (a >= 0 && a < 3 && b >= 0 && b < 3) v += kMask[3 * i + j] * static_cast<double>(k[3 * a + b]);
        }
      nk2 += v * v;
    }
  for (float x : k) k2 += static_cast<double>(x) * x;
  return std::sqrt(std::numbers::pi / 2) / std::sqrt(nk2 / k2) * sum / static_cast<double>(n);
}

FeatureDetector::FeatureDetector(int width, int height, const FeatureSettings& s)
    : s_(s), w_(width), h_(height) {
  const std::size_t np = static_cast<std::size_t>(w_) * h_;
  const std::size_t ni = static_cast<std::size_t>(w_ + 1) * (h_ + 1);
  gx_.assign(np, 0.f);
  gy_.assign(np, 0.f);
  ixx_.assign(ni, 0.0);
  ixy_.assign(ni, 0.0);
  iyy_.assign(ni, 0.0);
}

double FeatureDetector::min_eig_needed(double noise_sigma) const {
  // lambda_min needed for the shift sigma bound: sigma_t^2 = 2 sigma_n^2 / lambda_min (two noisy images).
  return 2.0 * noise_sigma * noise_sigma / (s_.max_shift_sigma_px * s_.max_shift_sigma_px);
}

double FeatureDetector::window_min_eig(int u, int v) const {
  const int W = w_ + 1, rad = s_.window_radius;
  const int c0 = u - rad, r0 = v - rad, c1 = u + rad + 1, r1 = v + rad + 1;
  const auto box = [&](const std::vector<double>& I) {
    return I[static_cast<std::size_t>(r1) * W + c1] - I[static_cast<std::size_t>(r0) * W + c1] -
           I[static_cast<std::size_t>(r1) * W + c0] + I[static_cast<std::size_t>(r0) * W + c0];
  };
  const double a = box(ixx_), b = box(ixy_), d = box(iyy_);
  return 0.5 * (a + d) - std::sqrt(0.25 * (a - d) * (a - d) + b * b);
}

float FeatureDetector::min_eig_at(int u, int v) const {
  const int rad = s_.window_radius;
  if (u - rad < 0 || v - rad < 0 || u + rad + 1 > w_ || v + rad + 1 > h_) return -1.f;
  return static_cast<float>(window_min_eig(u, v));
}

void FeatureDetector::detect(const GrayView& img, const std::uint8_t* usable, double noise_sigma,
                             std::vector<Feature>& out) {
  out.clear();
  const int w = w_, h = h_;
  // Central differences, the gradient the sub-pixel matcher uses (lk_affine.cpp).
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * w + c;
      gx_[p] = (c > 0 && c + 1 < w) ? 0.5f * (img.at(c + 1, r) - img.at(c - 1, r)) : 0.f;
      gy_[p] = (r > 0 && r + 1 < h) ? 0.5f * (img.at(c, r + 1) - img.at(c, r - 1)) : 0.f;
    }
  const int W = w + 1;
  for (int r = 0; r < h; ++r) {
    double sxx = 0, sxy = 0, syy = 0;
    for (int c = 0; c < w; ++c) {
      const std::size_t p = static_cast<std::size_t>(r) * w + c;
      sxx += double(gx_[p]) * gx_[p];
      sxy += double(gx_[p]) * gy_[p];
      syy += double(gy_[p]) * gy_[p];
      const std::size_t q = static_cast<std::size_t>(r + 1) * W + c + 1,
                        qa = static_cast<std::size_t>(r) * W + c + 1;
      ixx_[q] = ixx_[qa] + sxx;
      ixy_[q] = ixy_[qa] + sxy;
      iyy_[q] = iyy_[qa] + syy;
    }
  }
  const double need = min_eig_needed(noise_sigma);
  const int rad = s_.window_radius, cell = s_.cell_px;
  for (int cr = 0; cr < h; cr += cell)
    for (int cc = 0; cc < w; cc += cell) {
      Feature best;
      best.min_eig = -1;
      for (int r = cr; r < std::min(h, cr + cell); ++r)
        for (int c = cc; c < std::min(w, cc + cell); ++c) {
          if (!usable[r * w + c]) continue;
          if (c - rad < 0 || r - rad < 0 || c + rad + 1 > w || r + rad + 1 > h) continue;
          const double lmin = window_min_eig(c, r);
          if (lmin > best.min_eig) best = Feature{c, r, static_cast<float>(lmin)};
        }
      if (best.min_eig >= need && best.min_eig > 0 && out.size() < out.capacity()) out.push_back(best);
    }
}

}  // namespace naneye::recon::scene
