#pragma once
// The frame's own statistics that the corner detector decides with (docs/corners.md, "Decisions"):
// the noise of the pixels as a function of their level, and the white balance of a GRBG mosaic.
//
// Noise: a photon-counting sensor's variance grows with the signal, var = a * DN + b (a: DN per
// electron, shot noise; b: read noise and quantisation, DN^2). It is estimated per frame from the
// finest diagonal wavelet coefficient d = (p00 - p01 - p10 + p11) / 2 of 2 x 2 blocks of same-site
// pixels (Donoho & Johnstone 1994: sigma = median|d| / 0.6745 for Gaussian noise): d is blind to a
// block's level, to linear shading and to edges along either axis, so the median per level bin is
// the noise even on a frame mostly covered by a board.
//
// White balance: on a grey board under white light, each site of the mosaic sees the same radiance
// times its channel's gain, plus the black level: site = k * G + o. (k, o) per site are the least
// squares line of the site's values against the mean of its G neighbours (Gb against its diagonal
// Gr neighbours first), so any gains and black level give the same luminance as a mono sensor.
#include <array>
#include <cmath>
#include <cstdint>

namespace naneye::recon {

struct RawImageView;

// Per-pixel noise variance of an image as a function of its level: var = a * level + b.
struct NoiseModel {
  double a = 0;           // DN^2 per DN (shot noise)
  double b = 1.0 / 12.0;  // DN^2 (read noise; at least the quantisation of integer DN: 1/12)
  int levels = 0;         // level bins the fit used (0: the default above, nothing measured)
  double variance(double level) const { return b + a * (level > 0 ? level : 0.0); }
};

// The linear map of each mosaic site to G-equivalent values, site index (row & 1) * 2 + (col & 1):
// value' = (value - offset) / gain. Identity for mono or when not estimated.
struct CfaBalance {
  std::array<float, 4> gain{1, 1, 1, 1};
  std::array<float, 4> offset{0, 0, 0, 0};
  bool valid = false;
};

// The standard normal quantile z with P(Z > z) = p (bisection on erfc; for settings, not per frame).
double upper_normal_quantile(double p);

// chi2_nu / nu at the upper quantile whose normal deviate is z (upper_normal_quantile), by Wilson
// and Hilferty's cube approximation (Johnson, Kotz, Balakrishnan 1994, Eq. 18.24):
// (1 - c + z sqrt(c))^3, c = 2 / (9 nu). Inline: the dense validity test takes it per pixel.
inline double chi2_upper_ratio(double nu, double z) {
  const double c = 2.0 / (9.0 * nu), t = 1.0 - c + z * std::sqrt(c);
  return t * t * t;
}

// 10-bit full scale (1023) less the quantum of 8-bit data scaled by 4 (255 x 4 = 1020): a value at
// or above it may be clipped, and says only that the light was at least that. The one clip level of
// the corner detector (noise blocks, the fit's weights, the Bayer clip mark, edge midpoints).
inline constexpr float kClipDn = 1020.0f;

// Work space of estimate_noise (a histogram per level bin, sized once).
class NoiseEstimator {
 public:
  static constexpr int kLevelBins = 64;  // 16 DN each over 10-bit values (8-bit images use 16)
  static constexpr float kLevelBinDn = 16.0f;
  static constexpr int kDevBins = 256;  // |d| in steps of 0.25 DN, up to 64 DN (sigma ~ 95 DN)
  static constexpr float kDevStepDn = 0.25f;

  // The noise of `img` (w x h floats, row-major) from same-site blocks (`step` 1: mono, 2: Bayer),
  // rows [row_lo, row_hi) and columns [0, col_end). Allocates nothing.
  // Blocks reaching the clip of their site (`clip_dn`, indexed (row & 1) * 2 + (col & 1) for a mosaic;
  // [0] for mono) are saturated and left out: a white-balanced mosaic's clipped sites land at
  // (1020 - offset) / gain, under 1020 for a gain above 1.
  NoiseModel estimate(const float* img, int w, int row_lo, int row_hi, int col_end, int step,
                      const std::array<float, 4>& clip_dn = {kClipDn, kClipDn, kClipDn, kClipDn});

 private:
  std::array<std::array<std::uint32_t, kDevBins>, kLevelBins> hist_{};
  std::array<std::uint32_t, kLevelBins> count_{};
  std::array<double, kLevelBins> level_sum_{};
};

// The white balance of a GRBG mosaic from its own values (rows [row_lo, row_hi)); cells whose
// values reach `clip_dn` (saturated: not linear) are left out. Invalid when too few cells vary.
CfaBalance estimate_cfa_balance(const RawImageView& image, int row_lo, int row_hi, float clip_dn = 1000.0f);

}  // namespace naneye::recon
