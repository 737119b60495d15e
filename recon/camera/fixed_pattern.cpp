#include "naneye/recon/camera/fixed_pattern.hpp"
#include "naneye/base/median.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace naneye::recon {
namespace {

// The pixels the pipeline reads (RawImageView's contract): rows and columns it ignores are copied.
struct Region {
  int r0, r1, c1;  // rows [r0, r1), columns [0, c1)
  bool contains(int r, int c) const { return r >= r0 && r < r1 && c >= 0 && c < c1; }
};

Region used_region(const RawImageView& v) {
  return {v.ignore_edge_rows, v.height - v.ignore_edge_rows, v.width - v.ignore_last_cols};
}

// 1.4826 x the median absolute deviation: the sd of the normal part, which a handful of defect
// pixels (a hot pixel is ~1000 DN off in the dark map) would otherwise dominate.
double robust_sd_of(std::vector<double> v) {
  if (v.size() < 2) return 0.0;
  const double m = base::upper_median(v);
  for (double& x : v) x = std::abs(x - m);
  return 1.4826 * base::upper_median(v);
}

// Per-pixel variance of the mean of n frames (the sample variance / n); 0 for one frame.
double variance_of_mean(double sum, double sq, int n) {
  if (n < 2) return 0.0;
  const double mean = sum / n;
  return std::max(0.0, (sq / n - mean * mean) * n / (n - 1)) / n;
}

}  // namespace

std::string FixedPatternSettings::validate() const {
  if (min_dark_frames < 2) return "min_dark_frames must be >= 2 (the maps' error needs a spread)";
  if (min_flat_frames < 2) return "min_flat_frames must be >= 2";
  if (gain_radius_px < 1 || gain_radius_px > 16) return "gain_radius_px must be in 1..16";
  if (!(min_flat_signal_dn > 0)) return "min_flat_signal_dn must be > 0";
  if (!(saturation_margin_dn >= 0) || !(white_dn > saturation_margin_dn)) return "bad saturation margin";
  if (!(min_gain > 0 && min_gain < 1 && max_gain > 1)) return "gain range must hold 1";
  if (!(max_dark_spread_dn > 0)) return "max_dark_spread_dn must be > 0";
  return {};
}

FixedPatternBuilder::FixedPatternBuilder(const FixedPatternSettings& s) : s_(s) {
  if (auto e = s_.validate(); !e.empty()) throw std::invalid_argument("fixed pattern: " + e);
}

void FixedPatternBuilder::check_shape(const RawImageView& f) {
  if (!f.data || f.width <= 0 || f.height <= 0 || f.stride < f.width)
    throw std::invalid_argument("fixed pattern: empty frame");
  if (shape_.width == 0) {
    shape_ = f;
    shape_.data = nullptr;  // the first frame's geometry only
    const auto n = static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height);
    for (auto* v : {&dark_sum_, &dark_sq_, &flat_sum_, &flat_sq_}) v->assign(n, 0.0);
    return;
  }
  if (f.width != shape_.width || f.height != shape_.height || f.layout != shape_.layout)
    throw std::invalid_argument("fixed pattern: frames of another size or pixel layout than the first");
}

void FixedPatternBuilder::accumulate(const RawImageView& f, std::vector<double>& sum,
                                     std::vector<double>& sq) {
  check_shape(f);
  for (int r = 0; r < f.height; ++r)
    for (int c = 0; c < f.width; ++c) {
      const double v = f.data[static_cast<std::size_t>(r) * static_cast<std::size_t>(f.stride) +
                              static_cast<std::size_t>(c)];
      const auto k = static_cast<std::size_t>(r * f.width + c);
      sum[k] += v;
      sq[k] += v * v;
    }
}

void FixedPatternBuilder::add_dark(const RawImageView& f) {
  accumulate(f, dark_sum_, dark_sq_);
  ++dark_n_;
}

void FixedPatternBuilder::add_flat(const RawImageView& f) {
  accumulate(f, flat_sum_, flat_sq_);
  ++flat_n_;
}

FixedPattern FixedPatternBuilder::build() const {
  if (dark_n_ < s_.min_dark_frames)
    throw std::invalid_argument("fixed pattern: " + std::to_string(dark_n_) + " dark frames, need at least " +
                                std::to_string(s_.min_dark_frames));
  if (flat_n_ > 0 && flat_n_ < s_.min_flat_frames)
    throw std::invalid_argument("fixed pattern: " + std::to_string(flat_n_) + " flat frames, need at least " +
                                std::to_string(s_.min_flat_frames) + " (or none: offsets only)");
  const int w = shape_.width, h = shape_.height;
  const Region reg = used_region(shape_);
  const auto n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  FixedPattern p;
  p.width = w;
  p.height = h;
  p.dark_frames = dark_n_;
  p.flat_frames = flat_n_;
  p.dark.resize(n);
  std::vector<double> used_dark, se2;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const auto k = static_cast<std::size_t>(r * w + c);
      p.dark[k] = static_cast<float>(dark_sum_[k] / dark_n_);
      if (!reg.contains(r, c)) continue;
      used_dark.push_back(p.dark[k]);
      se2.push_back(variance_of_mean(dark_sum_[k], dark_sq_[k], dark_n_));
    }
  p.dsnu_dn = robust_sd_of(used_dark);
  if (p.dsnu_dn > s_.max_dark_spread_dn)
    throw std::invalid_argument("fixed pattern: the dark frames spread " +
                                std::to_string(static_cast<int>(std::lround(p.dsnu_dn))) +
                                " DN from pixel to pixel (a capped sensor's is a few DN): they saw light; "
                                "cap the lens");
  double mean_se2 = 0;
  for (double v : se2) mean_se2 += v;
  p.dark_se_dn = std::sqrt(mean_se2 / static_cast<double>(se2.size()));
  p.black_dn = static_cast<float>(base::upper_median(used_dark));
  if (flat_n_ == 0) return p;

  // The flat's signal per pixel, and its level: median and saturated share over the used pixels.
  std::vector<double> signal(n, 0.0), used_signal;
  int saturated = 0;
  for (int r = reg.r0; r < reg.r1; ++r)
    for (int c = 0; c < reg.c1; ++c) {
      const auto k = static_cast<std::size_t>(r * w + c);
      const double flat = flat_sum_[k] / flat_n_;
      signal[k] = flat - p.dark[k];
      used_signal.push_back(signal[k]);
      if (flat >= s_.white_dn - s_.saturation_margin_dn) ++saturated;
    }
  const double level = base::upper_median(used_signal);
  if (level < s_.min_flat_signal_dn)
    throw std::invalid_argument("fixed pattern: the flat frames' median signal is " +
                                std::to_string(static_cast<int>(std::lround(level))) +
                                " DN above dark, need at least " +
                                std::to_string(static_cast<int>(s_.min_flat_signal_dn)) + ": more light");
  // One pixel in a hundred near the top: the exposure is too long for a gain to be read off it.
  if (100 * saturated > static_cast<int>(used_signal.size()))
    throw std::invalid_argument("fixed pattern: " + std::to_string(saturated) +
                                " pixels of the flat frames are near saturation: less light");

  // Each pixel's gain against the median of its same-colour neighbours (the median: a defect
  // nearby must not move its neighbours' gains). Same colour = same row and column parity on a
  // Bayer mosaic, every pixel on a mono sensor.
  const int step = shape_.layout == PixelLayout::bayer_grbg ? 2 : 1;
  const int rad = s_.gain_radius_px;
  p.gain.assign(n, 1.0f);
  std::vector<double> neigh, used_gain, gain_se2;
  for (int r = reg.r0; r < reg.r1; ++r)
    for (int c = 0; c < reg.c1; ++c) {
      neigh.clear();
      for (int dr = -rad; dr <= rad; dr += step)
        for (int dc = -rad; dc <= rad; dc += step) {
          const int rr = r + dr, cc = c + dc;
          // Point-symmetric pairs only: at the border a one-sided window would read the shading's
          // slope as gain (0.2 % in the corners' 30 x 30 blocks), a symmetric one cancels it.
          if ((dr == 0 && dc == 0) || !reg.contains(rr, cc) || !reg.contains(r - dr, c - dc)) continue;
          neigh.push_back(signal[static_cast<std::size_t>(rr * w + cc)]);
        }
      if (neigh.size() < 8) continue;  // the first and last used rows: no symmetric neighbourhood
      const double local = base::upper_median(neigh);
      const auto k = static_cast<std::size_t>(r * w + c);
      if (local <= 0) continue;
      const double g = signal[k] / local;
      if (g < s_.min_gain || g > s_.max_gain) continue;  // a defect: left to the defect test
      p.gain[k] = static_cast<float>(g);
      used_gain.push_back(g);
      gain_se2.push_back((variance_of_mean(flat_sum_[k], flat_sq_[k], flat_n_) +
                          variance_of_mean(dark_sum_[k], dark_sq_[k], dark_n_)) /
                         (local * local));
    }
  p.prnu = robust_sd_of(used_gain);
  double g2 = 0;
  for (double v : gain_se2) g2 += v;
  p.gain_se = gain_se2.empty() ? 0.0 : std::sqrt(g2 / static_cast<double>(gain_se2.size()));
  return p;
}

void remove_fixed_pattern(const FixedPattern& p, const RawImageView& in, std::uint16_t* out) {
  if (p.empty() || in.width != p.width || in.height != p.height || !in.data)
    throw std::invalid_argument("fixed pattern: a " + std::to_string(in.width) + " x " +
                                std::to_string(in.height) + " frame against a pattern of " +
                                std::to_string(p.width) + " x " + std::to_string(p.height));
  const Region reg = used_region(in);
  constexpr int kTop = 1023;  // driver::kPixelMax: recon does not depend on the driver
  const bool gain = !p.gain.empty();
  for (int r = 0; r < in.height; ++r) {
    const std::uint16_t* src = in.data + static_cast<std::size_t>(r) * static_cast<std::size_t>(in.stride);
    std::uint16_t* dst = out + static_cast<std::size_t>(r) * static_cast<std::size_t>(in.width);
    const bool row_used = r >= reg.r0 && r < reg.r1;
    const float* dark = p.dark.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(p.width);
    const float* g =
        gain ? p.gain.data() + static_cast<std::size_t>(r) * static_cast<std::size_t>(p.width) : nullptr;
    for (int c = 0; c < in.width; ++c) {
      if (!row_used || c >= reg.c1 || src[c] >= kTop) {
        dst[c] = src[c];
        continue;
      }
      float v = static_cast<float>(src[c]) - dark[c];
      if (g) v /= g[c];
      dst[c] = static_cast<std::uint16_t>(std::clamp(std::lround(v + p.black_dn), 0L, long{kTop}));
    }
  }
}

RawImageView remove_fixed_pattern(const FixedPattern& p, const RawImageView& in,
                                  std::vector<std::uint16_t>& buffer) {
  buffer.resize(static_cast<std::size_t>(in.width) * static_cast<std::size_t>(in.height));
  remove_fixed_pattern(p, in, buffer.data());
  RawImageView v = in;
  v.data = buffer.data();
  v.stride = in.width;
  return v;
}

}  // namespace naneye::recon
