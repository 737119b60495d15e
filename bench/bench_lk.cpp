// The sparse path's affine LK (recon/scene/lk_affine.hpp) and its inner loop, the target's cubic
// B-spline sampled at every warped template point (lk_sample.hpp), beside OpenCV's cv::remap (bicubic,
// the same 16 taps per point) on the same points.
//
//   ./build/bench/bench_lk
//
// Counters: items_per_second = points sampled per second; time_per_fit = one refine_affine from a
// start 0.3 px off (its iterations and the statistics after), seconds SI-prefixed ("16u" = 16 us). Windows 9
// x 9 (the narrow match) and 21 x 21 (the widest step of the nested widening). The image: band-limited
// texture (sums of sines, periods 3-20 px) at 250 x 250; the right eye the same shifted by (3.3, 0.2) px.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "../recon/corners/simd.hpp"
#include "../recon/scene/lk_sample.hpp"
#include "naneye/recon/scene/bspline.hpp"
#include "naneye/recon/scene/lk_affine.hpp"

namespace {

using naneye::recon::scene::GrayView;
namespace scene = naneye::recon::scene;

constexpr int kSize = 250;
constexpr double kShiftX = 3.3, kShiftY = 0.2;

double texture(double x, double y) {
  return 500 + 120 * std::sin(0.9 * x + 0.3 * y) + 90 * std::sin(0.41 * x - 0.77 * y + 1) +
         70 * std::sin(0.31 * y + 2) + 60 * std::sin(1.7 * x + 1.1 * y + 0.5);
}

struct Images {
  std::vector<float> left, right, spline, scratch, gx, gy;
  std::vector<std::uint8_t> usable;
  Images() {
    const std::size_t n = static_cast<std::size_t>(kSize) * kSize;
    left.resize(n);
    right.resize(n);
    spline.resize(n);
    scratch.resize(n);
    gx.assign(n, 0.f);
    gy.assign(n, 0.f);
    usable.assign(n, 1);
    for (int r = 0; r < kSize; ++r)
      for (int c = 0; c < kSize; ++c) {
        left[static_cast<std::size_t>(r * kSize + c)] = static_cast<float>(texture(c, r));
        right[static_cast<std::size_t>(r * kSize + c)] =
            static_cast<float>(texture(c - kShiftX, r - kShiftY));
      }
    scene::bspline_coefficients({right.data(), kSize, kSize}, {kSize, 0, kSize}, spline.data(),
                                scratch.data());
    for (int r = 1; r + 1 < kSize; ++r)
      for (int c = 1; c + 1 < kSize; ++c) {
        const std::size_t p = static_cast<std::size_t>(r * kSize + c);
        gx[p] = 0.5f * (left[p + 1] - left[p - 1]);
        gy[p] = 0.5f * (left[p + kSize] - left[p - kSize]);
      }
  }
};

const Images& images() {
  static const Images im;
  return im;
}

// The window's template offsets, slightly off the grid as the exact model's shape makes them.
void window(int radius, std::vector<float>& qx, std::vector<float>& qy) {
  const int side = 2 * radius + 1, n = side * side;
  qx.resize(static_cast<std::size_t>(n));
  qy.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    qx[static_cast<std::size_t>(k)] = static_cast<float>(k % side - radius) * 1.013f + 0.002f * (k % 7);
    qy[static_cast<std::size_t>(k)] = static_cast<float>(k / side - radius) * 0.991f;
  }
}

// Args: radius, lanes (1, 4, 8).
void BM_LkSampleWindow(benchmark::State& state) {
  const int radius = static_cast<int>(state.range(0)), lanes = static_cast<int>(state.range(1));
  if (lanes == 8 && !naneye::recon::simd::has_avx2()) {
    state.SkipWithError("no AVX2 on this CPU");
    return;
  }
  const Images& im = images();
  std::vector<float> qx, qy;
  window(radius, qx, qy);
  const int n = static_cast<int>(qx.size());
  std::vector<float> out(qx.size());
  const scene::lk_sample::Warp w{{1.02f, 0.03f, 120.3f, -0.02f, 0.99f, 110.7f}};
  const GrayView view{im.spline.data(), kSize, kSize};
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        scene::lk_sample::sample_window_lanes(lanes, view, w, qx.data(), qy.data(), n, out.data()));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_LkSampleWindow)->ArgsProduct({{4, 10}, {1, 4, 8}});

// The anchor: cv::remap, bicubic (Keys, a = -0.75), over the same warped points as a 1 x n map.
void BM_OpenCvRemapWindow(benchmark::State& state) {
  const int radius = static_cast<int>(state.range(0));
  const Images& im = images();
  std::vector<float> qx, qy;
  window(radius, qx, qy);
  const int n = static_cast<int>(qx.size());
  cv::Mat mx(1, n, CV_32F), my(1, n, CV_32F), out;
  for (int k = 0; k < n; ++k) {
    mx.at<float>(k) =
        1.02f * qx[static_cast<std::size_t>(k)] + 0.03f * qy[static_cast<std::size_t>(k)] + 120.3f;
    my.at<float>(k) =
        -0.02f * qx[static_cast<std::size_t>(k)] + 0.99f * qy[static_cast<std::size_t>(k)] + 110.7f;
  }
  const cv::Mat src(kSize, kSize, CV_32F, const_cast<float*>(im.right.data()));
  for (auto _ : state) {
    cv::remap(src, out, mx, my, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
    benchmark::DoNotOptimize(out.data);
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_OpenCvRemapWindow)->Arg(4)->Arg(10);

// One refine_affine as the sparse path calls it (the widest with the inner ring's statistics and the
// curvature gain), from 0.3 px off the true shift.
void BM_RefineAffine(benchmark::State& state) {
  const int radius = static_cast<int>(state.range(0));
  const Images& im = images();
  scene::LkSettings s;
  s.radius = radius;
  s.inner_radius = radius > 4 ? radius - 2 : 0;
  s.curvature_gain = true;
  const int u = 120, v = 110;
  const Eigen::Vector2d start(u + kShiftX + 0.3, v + kShiftY - 0.1);
  int iterations = 0;
  double fits = 0;
  for (auto _ : state) {
    const scene::LkResult r = scene::refine_affine({im.left.data(), kSize, kSize}, im.gx.data(), im.gy.data(),
                                                   u, v, {im.spline.data(), kSize, kSize}, im.usable.data(),
                                                   start, Eigen::Matrix2d::Identity(), nullptr, s);
    benchmark::DoNotOptimize(r.px.data());
    iterations = r.iterations;
    ++fits;
  }
  state.counters["iterations"] = iterations;
  state.counters["time_per_fit"] =
      benchmark::Counter(fits, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_RefineAffine)->Arg(4)->Arg(10);

}  // namespace

BENCHMARK_MAIN();
