// The frame's noise model and white balance (corners/noise.hpp).
#include "naneye/recon/corners/noise.hpp"

#include <algorithm>
#include <cmath>

#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

namespace {
// A level bin enters the fit with at least this many blocks: the median of n |d| has a relative
// standard error ~1.25 / sqrt(n) (asymptotic variance of the median of a half-normal), 18 % at 48.
constexpr std::uint32_t kMinBlocks = 48;
// median |d| / sigma for Gaussian d (the 75th percentile of the standard normal).
constexpr double kMadToSigma = 0.6744897501960817;
// Bins whose variance exceeds the first fit by this factor are taken as contaminated by structure
// (corners, diagonal edges: d only grows with it) and left out of the second fit. A bin of 48
// blocks lies within a factor 1.5 of the truth in variance with p ~ 0.99, so 2 rejects structure only.
constexpr double kContaminated = 2.0;
// A level range narrower than this (DN) cannot separate a from b: the model is then a constant.
constexpr double kMinLevelSpanDn = 48.0;

struct Line {
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  void add(double w, double x, double y) {
    sw += w;
    sx += w * x;
    sy += w * y;
    sxx += w * x * x;
    sxy += w * x * y;
  }
};
}  // namespace

double upper_normal_quantile(double p) {
  double lo = 0, hi = 40;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

NoiseModel NoiseEstimator::estimate(const float* img, int w, int row_lo, int row_hi, int col_end, int step,
                                    const std::array<float, 4>& clip_dn) {
  // The data's quantum: the smallest nonzero |a - b - e + f| of integer data is its step (1 for
  // 10-bit DN, 4 for 8-bit images scaled to 10 bits); the quantisation's variance step^2 / 12 is
  // the least noise the decisions may assume (JPEG's smoothing can leave flat areas quieter).
  float quantum = 1e30f;
  for (auto& h : hist_) h.fill(0);
  count_.fill(0);
  level_sum_.fill(0.0);
  // Non-overlapping 2 x 2 blocks of same-site pixels (step 2: the four sites of a Bayer mosaic each
  // form their own blocks), so every d is independent of every other.
  for (int r0 = row_lo; r0 + 2 * step <= row_hi; r0 += 2 * step) {
    for (int dr = 0; dr < step; ++dr) {
      const float* p = img + static_cast<std::ptrdiff_t>(r0 + dr) * w;
      const float* q = p + static_cast<std::ptrdiff_t>(step) * w;
      for (int c0 = 0; c0 + 2 * step <= col_end; c0 += 2 * step) {
        for (int c = c0; c < c0 + step; ++c) {
          const float a = p[c], b = p[c + step], e = q[c], f = q[c + step];
          // Saturated blocks carry no noise (and 8-bit images scaled to 10 bits end at 1020).
          const float clip = clip_dn[step == 1 ? 0 : static_cast<std::size_t>(((r0 + dr) & 1) * 2 + (c & 1))];
          if (std::max(std::max(a, b), std::max(e, f)) >= clip) continue;
          const float level = 0.25f * (a + b + e + f);
          const int lb = std::clamp(static_cast<int>(level / kLevelBinDn), 0, kLevelBins - 1);
          const float dd = std::abs(a - b - e + f);
          if (dd > 0.0f && dd < quantum) quantum = dd;
          const int db = std::min(static_cast<int>(dd * (0.5f / kDevStepDn)), kDevBins - 1);
          ++hist_[static_cast<std::size_t>(lb)][static_cast<std::size_t>(db)];
          ++count_[static_cast<std::size_t>(lb)];
          level_sum_[static_cast<std::size_t>(lb)] += level;
        }
      }
    }
  }
  std::array<double, kLevelBins> var{}, lev{}, wt{};
  int bins = 0;
  for (int i = 0; i < kLevelBins; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (count_[k] < kMinBlocks) continue;
    const double half = 0.5 * count_[k];
    double acc = 0;
    int j = 0;
    while (j < kDevBins && acc + hist_[k][static_cast<std::size_t>(j)] < half)
      acc += hist_[k][static_cast<std::size_t>(j++)];
    if (j >= kDevBins - 1) continue;  // half the blocks beyond the histogram: structure, not noise
    const double in_bin = hist_[k][static_cast<std::size_t>(j)];
    const double median = (j + (half - acc) / std::max(in_bin, 1.0)) * kDevStepDn;
    const double s = median / kMadToSigma;
    var[k] = s * s;
    lev[k] = level_sum_[k] / count_[k];
    // The variance of a variance estimate grows with its square: weights n / var^2 (floored at the
    // quantisation's variance so that a noise-free bin does not take all the weight).
    const double v = std::max(var[k], 1.0);
    wt[k] = count_[k] / (v * v);
    ++bins;
  }
  const double q = quantum > 64.0f ? 1.0 : static_cast<double>(quantum);
  const double floor_var = std::max(1.0, q * q) / 12.0;
  NoiseModel m;
  m.b = floor_var;
  if (bins == 0) return m;
  auto fit = [&](const NoiseModel* prev) {
    Line l;
    double lo = 1e30, hi = -1e30;
    int used = 0;
    for (std::size_t k = 0; k < var.size(); ++k) {
      if (wt[k] <= 0) continue;
      if (prev && var[k] > kContaminated * prev->variance(lev[k])) continue;
      l.add(wt[k], lev[k], var[k]);
      lo = std::min(lo, lev[k]);
      hi = std::max(hi, lev[k]);
      ++used;
    }
    NoiseModel out;
    out.b = floor_var;
    out.levels = used;
    if (used == 0) return prev ? *prev : out;
    const double det = l.sw * l.sxx - l.sx * l.sx;
    if (hi - lo >= kMinLevelSpanDn && det > 0) {
      out.a = (l.sw * l.sxy - l.sx * l.sy) / det;
      out.b = (l.sy - out.a * l.sx) / l.sw;
    }
    if (hi - lo < kMinLevelSpanDn || det <= 0 || out.a < 0) {
      out.a = 0;
      out.b = l.sy / l.sw;
    }
    if (out.b < floor_var) {
      // Read noise below the quantisation is not physical: fix b there and fit a alone.
      out.b = floor_var;
      if (l.sxx > 0) out.a = std::max(0.0, (l.sxy - out.b * l.sx) / l.sxx);
    }
    return out;
  };
  m = fit(nullptr);
  m = fit(&m);
  return m;
}

namespace {
// Least-squares line y = k x + o over the mosaic's cells of one site type against the mean of
// their G neighbours, skipping saturated cells and, on the second pass, cells on an edge (their
// neighbours' spread beyond 4 standard deviations of the first pass's residual): the mean of the
// neighbours is the centre's value only where the light is locally linear.
struct SiteFit {
  double k = 1, o = 0, resid_sd = 0, se_k = 1e9;
};

template <typename Neighbours>
SiteFit fit_site(const RawImageView& im, int site_r, int site_c, int r_lo, int r_hi, int c_lo, int c_hi,
                 float clip, double max_spread, Neighbours nb) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  // Every other row of the site (a 250 x 250 frame still gives ~8000 cells per site: slope errors
  // ~1e-4), which halves the cost.
  for (int r = r_lo + ((r_lo & 1) != site_r); r < r_hi; r += 4) {
    const std::uint16_t* row = im.data + static_cast<std::ptrdiff_t>(r) * im.stride;
    for (int c = c_lo + ((c_lo & 1) != site_c); c < c_hi; c += 2) {
      const float y = row[c];
      std::array<float, 4> v;
      nb(r, c, v);
      const auto [mn, mx] = std::minmax_element(v.begin(), v.end());
      if (y >= clip || *mx >= clip || *mn <= 0.0f || *mx - *mn > max_spread) continue;
      const double x = 0.25 * (v[0] + v[1] + v[2] + v[3]);
      n += 1;
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
      syy += static_cast<double>(y) * y;
    }
  }
  SiteFit f;
  if (n < 16) return f;
  const double vx = sxx / n - (sx / n) * (sx / n), cxy = sxy / n - (sx / n) * (sy / n);
  const double vy = syy / n - (sy / n) * (sy / n);
  if (!(vx > 0)) return f;
  f.k = cxy / vx;
  f.o = sy / n - f.k * sx / n;
  const double rv = std::max(0.0, vy - f.k * cxy);
  f.resid_sd = std::sqrt(rv);
  f.se_k = std::sqrt(rv / (n * vx));
  return f;
}
}  // namespace

CfaBalance estimate_cfa_balance(const RawImageView& im, int row_lo, int row_hi, float clip_dn) {
  CfaBalance out;
  if (im.layout != PixelLayout::bayer_grbg || !im.data) return out;
  // Cells with all neighbours inside the usable area (reference rows, padding columns left out).
  const int r_lo = std::max(row_lo, im.ignore_edge_rows + 1);
  const int r_hi = std::min(row_hi, im.height - im.ignore_edge_rows - 1);
  const int c_lo = 1, c_hi = im.width - im.ignore_last_cols - 1;
  if (r_hi - r_lo < 4 || c_hi - c_lo < 4) return out;
  auto px = [&](int r, int c) {
    return static_cast<float>(im.data[static_cast<std::ptrdiff_t>(r) * im.stride + c]);
  };
  // A slope this uncertain (standard error) is no white balance: the frame lacks contrast.
  constexpr double kMaxSlopeError = 0.01;
  // Pass 1 uses every cell; pass 2 only those whose neighbours spread less than 4 standard
  // deviations of pass 1's residual for that site (at least 4 DN: the quantisation of 8-bit input).
  std::array<double, 4> sd{1e30, 1e30, 1e30, 1e30};
  for (int pass = 0; pass < 2; ++pass) {
    auto spread = [&](int site) {
      return pass == 0 ? 1e30 : 4.0 * std::max(sd[static_cast<std::size_t>(site)], 1.0);
    };
    // GRBG: site 0 = Gr (even row, even column), 1 = R, 2 = B, 3 = Gb.
    const SiteFit gb = fit_site(
        im, 1, 1, r_lo, r_hi, c_lo, c_hi, clip_dn, spread(3), [&](int r, int c, std::array<float, 4>& v) {
          v = {px(r - 1, c - 1), px(r - 1, c + 1), px(r + 1, c - 1), px(r + 1, c + 1)};
        });
    const float kg = static_cast<float>(gb.k), og = static_cast<float>(gb.o);
    auto g_eq = [&](float gbv) { return (gbv - og) / kg; };  // Gb in Gr units
    const SiteFit r = fit_site(im, 0, 1, r_lo, r_hi, c_lo, c_hi, clip_dn, spread(1),
                               [&](int rr, int c, std::array<float, 4>& v) {
                                 v = {px(rr, c - 1), px(rr, c + 1), g_eq(px(rr - 1, c)), g_eq(px(rr + 1, c))};
                               });
    const SiteFit b = fit_site(im, 1, 0, r_lo, r_hi, c_lo, c_hi, clip_dn, spread(2),
                               [&](int rr, int c, std::array<float, 4>& v) {
                                 v = {g_eq(px(rr, c - 1)), g_eq(px(rr, c + 1)), px(rr - 1, c), px(rr + 1, c)};
                               });
    if (gb.se_k > kMaxSlopeError || r.se_k > kMaxSlopeError || b.se_k > kMaxSlopeError || !(gb.k > 0) ||
        !(r.k > 0) || !(b.k > 0)) {
      return CfaBalance{};
    }
    out.gain = {1.0f, static_cast<float>(r.k), static_cast<float>(b.k), kg};
    out.offset = {0.0f, static_cast<float>(r.o), static_cast<float>(b.o), og};
    out.valid = true;
    sd = {0.0, r.resid_sd, b.resid_sd, gb.resid_sd};
  }
  return out;
}

}  // namespace naneye::recon
