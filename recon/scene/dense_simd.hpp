#pragma once
// The dense sub-pixel step's plane kernels (dense_subpixel.cpp): the window sums and the residual's
// lag filter, written once over a GCC vector type and compiled twice, 4 floats (SSE2, the x86-64
// baseline) and 8 floats (AVX2), chosen at run time as corners/simd.hpp does. They add and multiply
// in the scalar loops' order and never fuse a multiply-add (the AVX2 code is built without FMA), so
// both give the scalar code's bits: the dense results do not depend on the machine.
#include <cstddef>
#include <cstdint>

namespace naneye::recon::scene::dense_simd {

// The rows' spans of left data (RectifiedMatcher::span_lo_, span_hi_): the per-pixel work runs
// only there, ~70 % of the rectified grid (its band columns and the domain disc's corners carry
// nothing).
struct Spans {
  const int *lo, *hi;
  int w, h;
  template <class F>
  void each(F&& f) const {
    for (int y = 0; y < h; ++y)
      for (int x = lo[y]; x < hi[y]; ++x) f(static_cast<std::size_t>(y) * w + x);
  }
};

// Sum over the (2r+1)^2 window (zero outside the image), output inside the spans only (`in` is zero
// outside them); `tmp` holds w floats.
void box_sum(bool avx2, const float* in, float* out, float* tmp, const Spans& sp, int r);

// out += rho * z inside the spans, rho over lags [-lag, lag]^2 (row-major), z zero outside the
// image and the spans.
void filter_lags(bool avx2, const float* z, float* out, const float* rho, int lag, const Spans& sp);

// The residual's autocorrelation sums (RectifiedMatcher::correlation): acc[(dy + 3) * 7 + dx + 3]
// = sum of e_p * e_(p + (dx, dy)) over lags [-3, 3]^2 and the pixels p of every other row and column
// from (3, 3) on, at least 3 from the far borders, with e_p != 0; each product in float, summed in
// double in the pixels' order (the plain loop's bits). e: w x h.
void lag_products(bool avx2, const float* e, int w, int h, double acc[49]);

// One rectified row of the sub-pixel step's per-pixel products (RectifiedMatcher::gather): the cubic
// B-spline over the right row's coefficients at x - d (W) and the left pixel (l), both less mu, the
// left's gradient (G, from left_grad), and the ten channels m, W, l, G, WW, GG, WG, Wl, Gl, ll (m = 1
// where every tap lies inside the right's valid domain and the left has a gradient, else all zero).
struct GatherRow {
  const float* left;       // left row
  const float* left_grad;  // the left row's gradient (RectifiedMatcher::left_gradient; NaN: none)
  const float* right;      // right row's B-spline coefficients (bspline_coefficients_line per valid run)
  // taps_ok[i]: right pixels i - 1 .. i + 2 all valid (only read for 1 <= i < w - 2)
  const std::uint8_t* taps_ok;
  const float* d;  // the row's reference disparities (NaN: none)
  float* ch[10];   // the ten channel planes, at this row
  int lo, hi, w;   // columns [lo, hi) of a w-wide row
  float mu;        // the level subtracted from both images
};
void gather_row(bool avx2, const GatherRow& g);

// One row of an earlier Gauss-Newton iteration's step (RectifiedMatcher::refine; dense_step.cpp), in
// float, over columns [lo, hi): from the window sums N, W, L, G, WW, GG, WG, WL, GL (s[0..8] at this row) the
// centred 2 x 2 system, its step nc / det clamped to half a pixel. Per pixel: no disparity (d NaN),
// no data (m == 0) or fewer than 4 window pixels, or det <= 0: d = NaN, out = solved = 0; na <= 0
// (anti-correlated): out = solved = 0; else out = d + step, solved = 1.
struct StepRow {
  const float* s[9];
  const float* m;  // the gather's mask channel
  float* d;        // reference disparities (in; NaN where refused)
  float* out;      // d + step where solved, else 0
  float* solved;   // 1 where solved, else 0
  int lo, hi;
};
void step_row(bool avx2, const StepRow& r);

// One row of the last Gauss-Newton iteration's fit (RectifiedMatcher::refine), in double, over
// columns [lo, hi) (dense_fit.cpp). From the window sums s[0..9] (N, W, L, G, WW, GG, WG, WL, GL, LL)
// at this row: n = N, step = solved = 0; no disparity, no data, N < 4 or det <= 0: d = NaN and nothing
// else written; else the fit's a, b, c, s2, z and centred sums, and where a > 0 the step c clamped
// to half a pixel, solved = 1. The AVX2 build computes 4 pixels at once in the scalar loop's order.
struct FitRow {
  const float* s[10];
  const float* m;  // the gather's mask channel
  float* d;        // reference disparities (in; NaN where refused)
  float *n, *step, *solved, *a, *b, *c, *s2, *z, *sww, *swg, *sgg;
  int lo, hi;
};
void fit_row(bool avx2, const FitRow& r);

// One row of window_detail()'s solve (RectifiedMatcher, dense_subpixel.cpp), in double over [lo, hi):
// from the fit's sums s[0, 1, 3, 4, 5, 6] (N, W, G, WW, GG, WG), the detail's s[7] = sum WGq,
// s[8] = sum GGq and sgq = sum Gq, out = (Sww ggq_c - Swg wgq_c) / det (0 where N < 4 or det <= 0).
struct DetailRow {
  const float* s[9];
  const float* sgq;
  float* out;
  int lo, hi;
};
void detail_row(bool avx2, const DetailRow& r);

// One row of the last iteration's update (RectifiedMatcher::refine) over [lo, hi): d = NaN where not
// solved, else d += step + (move if both the detail q and move = q_win - q lie within 3 sigma =
// 3 sqrt(s2 z), else 0).
struct UpdateRow {
  const float *solved, *step, *q, *q_win, *s2, *z;
  float* d;
  int lo, hi;
};
void update_row(bool avx2, const UpdateRow& r);

// correlation()'s per-pixel steps (dense_fit.cpp), over [lo, hi) of the given planes:
// residual: e = a W + b - c G - L where m > 0, d is finite and s2 <= lim, else 0;
// centre: z = G - sum G / max(1, N) where m > 0, else 0; zz = z^2; zh = 0;
// kappa: k = max(0, szh / szz) where szz > 0, else 1.
struct ResidualRow {
  const float *m, *w, *l, *g, *d, *s2, *a, *b, *c;
  float* e;
};
void residual_row(bool avx2, const ResidualRow& r, double lim, std::size_t lo, std::size_t hi);
void centre_row(bool avx2, const float* m, const float* g, const float* sg, const float* sn, float* z,
                float* zz, float* zh, int lo, int hi);
void kappa_row(bool avx2, const float* szz, const float* szh, float* kappa, int lo, int hi);

// One row of the earlier iterations' window mean (RectifiedMatcher::refine) over [lo, hi), where d is
// finite: next = sum / cnt (d where cnt <= 0), moved = next - d, d = next.
void mean_row(bool avx2, const float* sum, const float* cnt, float* d, float* moved, int lo, int hi);

}  // namespace naneye::recon::scene::dense_simd
