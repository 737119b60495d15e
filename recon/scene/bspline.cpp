// See bspline.hpp. The prefilter is the inverse of the sampled B-spline, 6 / (z + 4 + 1/z): a causal
// and an anti-causal first-order recursion with the pole z1 = sqrt(3) - 2 and the gain 6 (Unser 1999,
// Box 2), down the columns (all columns at once: whole rows as vectors) and then along the rows (the
// same, on the block transposed by OpenCV). A recursion along each row on its own was 3.0 M
// instructions per image (callgrind), latency-bound and unvectorised.
#include "naneye/recon/scene/bspline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "../corners/simd.hpp"

namespace naneye::recon::scene {
namespace {

constexpr float kPole = -0.267949192431122706f;  // sqrt(3) - 2
// Each pass's gain (the 2-D prefilter applies both passes' at once, to the samples as they are
// copied in).
constexpr float kGain = 6.0f, kGain2 = kGain * kGain;
// The anti-causal start's factor, z1 / (z1^2 - 1).
constexpr float kEnd = kPole / (kPole * kPole - 1.0f);
// Terms of the causal start's sum: |z1|^16 = 7e-10, below float's resolution of the sum.
constexpr int kHorizon = 16;

// Index k of a line of n samples continued as its mirror image (period 2 n - 2).
int mirror(int k, int n) {
  const int period = 2 * n - 2;
  k %= period;
  if (k < 0) k += period;
  return k < n ? k : period - k;
}

// dst[j] = f(dst[j], src[j]) for j < n: 4 lanes at a time (GCC vectorises no loop at -O2 whose
// trip count it does not know), then the tail.
template <class F>
void over_row(float* __restrict dst, const float* __restrict src, int n, F f) {
  using simd::V4;
  int j = 0;
  for (; j + 4 <= n; j += 4) simd::store(dst + j, f(simd::load<V4>(dst + j), simd::load<V4>(src + j)));
  for (; j < n; ++j) dst[j] = f(dst[j], src[j]);
}

// Every column of a rows x cols block (rows `stride` apart) filtered down its length in place, whole
// rows at a time. rows > kHorizon: the causal start's terms k < kHorizon are rows 1.. of the block
// itself, never the row being summed into.
void filter_columns(float* p, int rows, int cols, std::ptrdiff_t stride) {
  // Causal start, c+[0] = sum_k z1^k s[k] over the mirrored column (Unser 1999, Box 2).
  float zk = kPole;
  for (int k = 1; k < kHorizon; ++k, zk *= kPole)
    over_row(p, p + k * stride, cols, [zk](auto first, auto row) { return first + zk * row; });
  // c+[k] = s[k] + z1 c+[k-1].
  for (int k = 1; k < rows; ++k)
    over_row(p + k * stride, p + (k - 1) * stride, cols,
             [](auto cur, auto prev) { return cur + kPole * prev; });
  // c-[n-1] = z1 / (z1^2 - 1) (c+[n-1] + z1 c+[n-2]); then c-[k] = z1 (c-[k+1] - c+[k]).
  over_row(p + (rows - 1) * stride, p + (rows - 2) * stride, cols,
           [](auto last, auto before) { return kEnd * (last + kPole * before); });
  for (int k = rows - 2; k >= 0; --k)
    over_row(p + k * stride, p + (k + 1) * stride, cols,
             [](auto cur, auto next) { return kPole * (next - cur); });
}

// The prefilter's impulse response h_k = sqrt(3) z1^|k| (the coefficients of a unit sample; Unser
// 1999, Box 2), in double: the interpolant's analysis below builds on it.
double prefilter_tap(int k) {
  return std::sqrt(3.0) * std::pow(std::sqrt(3.0) - 2.0, std::abs(k));
}

}  // namespace

void bspline_coefficients_line(const float* in, int n, float* out) {
  if (n < 2) throw std::invalid_argument("bspline_coefficients_line: a line needs 2 samples");
  // The causal start reads the input before out[0] is written (they may alias).
  float acc = 0, zk = 1;
  for (int k = 0; k < kHorizon; ++k, zk *= kPole) acc += zk * in[mirror(k, n)];
  out[0] = kGain * acc;
  for (int k = 1; k < n; ++k) out[k] = kGain * in[k] + kPole * out[k - 1];
  out[n - 1] = kEnd * (out[n - 1] + kPole * out[n - 2]);
  for (int k = n - 2; k >= 0; --k) out[k] = kPole * (out[k + 1] - out[k]);
}

void bspline_coefficients(const GrayView& in, const ActiveRect& a, float* out, float* scratch) {
  const int w = in.width, h = in.height, rows = a.row_end - a.row_begin;
  if (a.cols <= kHorizon || rows <= kHorizon || a.cols > w || a.row_begin < 0 || a.row_end > h)
    throw std::invalid_argument(
        "bspline_coefficients: the active rectangle must be at least 17 x 17 inside the image");
  float* first = out + static_cast<std::ptrdiff_t>(a.row_begin) * w;
  for (int r = 0; r < rows; ++r) {
    const float* src = in.data + static_cast<std::ptrdiff_t>(r + a.row_begin) * w;
    float* dst = first + static_cast<std::ptrdiff_t>(r) * w;
    over_row(dst, src, a.cols, [](auto, auto x) { return kGain2 * x; });
  }
  filter_columns(first, rows, a.cols, w);
  // Along the rows: the same filter down the columns of the transposed block.
  // Headers over the caller's buffers: cv::transpose writes into them (their size and type already
  // match), nothing is allocated.
  const cv::Mat block(rows, a.cols, CV_32FC1, first, static_cast<std::size_t>(w) * sizeof(float));
  cv::Mat flipped(a.cols, rows, CV_32FC1, scratch);
  cv::transpose(block, flipped);
  filter_columns(scratch, a.cols, rows, rows);
  cv::transpose(flipped, block);
  // Beyond the rectangle: the mirrored coefficients.
  for (int r = a.row_begin; r < a.row_end; ++r) {
    float* row = out + static_cast<std::ptrdiff_t>(r) * w;
    for (int c = a.cols; c < w; ++c) row[c] = row[mirror(c, a.cols)];
  }
  for (int r = 0; r < h; ++r) {
    if (r >= a.row_begin && r < a.row_end) continue;
    const int from = a.row_begin + mirror(r - a.row_begin, rows);
    std::copy_n(out + static_cast<std::ptrdiff_t>(from) * w, w, out + static_cast<std::ptrdiff_t>(r) * w);
  }
}

namespace {
constexpr int kNoiseSteps = 256;
using NoiseTable = std::array<std::array<double, kNoiseSteps + 1>, kNoiseLagReach + 1>;

const NoiseTable& noise_table() {
  constexpr int kReach = 24;  // |z1|^24 ~ 2e-14: the cardinal spline's taps beyond are 0
  // Immutable after its first use (a function-local static: built once, thread-safe).
  static const NoiseTable table = [] {
    const auto beta3 = [](double x) {
      x = std::abs(x);
      return x < 1 ? 2.0 / 3.0 - x * x + 0.5 * x * x * x : x < 2 ? (2 - x) * (2 - x) * (2 - x) / 6 : 0.0;
    };
    // eta(x) = sum_k h_k beta3(x - k): only the four k with |x - k| < 2.
    const auto eta = [&](double x) {
      const int k0 = static_cast<int>(std::floor(x)) - 1;
      double v = 0;
      for (int k = k0; k <= k0 + 3; ++k) v += prefilter_tap(k) * beta3(x - k);
      return v;
    };
    NoiseTable t{};
    for (int i = 0; i <= kNoiseSteps; ++i) {
      const double fi = static_cast<double>(i) / kNoiseSteps;
      double taps[2 * kReach + 1 + kNoiseLagReach];
      for (int j = -kReach; j <= kReach + kNoiseLagReach; ++j) taps[j + kReach] = eta(fi + j);
      for (int l = 0; l <= kNoiseLagReach; ++l) {
        double sum = 0;
        for (int j = 0; j < 2 * kReach + 1; ++j) sum += taps[j] * taps[j + l];
        t[static_cast<std::size_t>(l)][static_cast<std::size_t>(i)] = sum;
      }
    }
    return t;
  }();
  return table;
}

// Linear between the table's entries at f (clamped to [0, 1]).
double noise_entry(const NoiseTable& table, double f, int lag) {
  const double x = std::clamp(f, 0.0, 1.0) * kNoiseSteps;
  const int i = std::min(static_cast<int>(x), kNoiseSteps - 1);
  const auto& row = table[static_cast<std::size_t>(lag)];
  return row[static_cast<std::size_t>(i)] +
         (x - i) * (row[static_cast<std::size_t>(i) + 1] - row[static_cast<std::size_t>(i)]);
}
}  // namespace

double bspline_noise_autocorrelation(double f, int lag) {
  lag = std::abs(lag);
  if (lag > kNoiseLagReach)
    throw std::invalid_argument("bspline_noise_autocorrelation: lag beyond the table");
  return noise_entry(noise_table(), f, lag);
}

void bspline_noise_autocorrelations(double f, double (&out)[kNoiseLagReach + 1]) {
  const NoiseTable& table = noise_table();
  for (int lag = 0; lag <= kNoiseLagReach; ++lag) out[lag] = noise_entry(table, f, lag);
}

double bspline_knot_derivative_tap(int k) {
  if (k == 0 || std::abs(k) > kKnotDerivativeReach) return 0.0;
  return 0.5 * (prefilter_tap(k - 1) - prefilter_tap(k + 1));
}

}  // namespace naneye::recon::scene
