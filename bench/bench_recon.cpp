// Undistortion and triangulation, ours against OpenCV's, on the same points in one run.
//
//   ./build/bench/bench_recon
//
// Counters: time_per_pt (seconds per point, SI-prefixed: "95n" = 95 ns), max_err_px (largest
// round-trip error |distort(undistort(p)) - p| in pixels) and max_err_mm (largest 3D error against
// the noise-free truth). Inputs: the left Dataset 3 camera (config/calib/paper-d3.yaml), every
// pixel centre inside its valid domain plus as many random sub-pixel points inside it; for
// triangulation, 3D points on the rays of a left pixel lattice at 15-120 mm seen by both cameras.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <random>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/geometry/calibration_sigma_table.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"
#include "naneye/recon/geometry/triangulation.hpp"

namespace {

using naneye::recon::CameraModel;
using naneye::recon::StereoRig;

struct Data {
  StereoRig rig;
  // Undistortion inputs.
  std::vector<Eigen::Vector2d> px;
  cv::Mat px_cv;  // N x 1, CV_64FC2
  cv::Mat K_cv, D_cv;
  // Triangulation inputs (noise-free) and truth.
  std::vector<Eigen::Vector3d> X;
  std::vector<Eigen::Vector2d> pl, pr, xl, xr;
  cv::Mat xl_cv, xr_cv;  // 2 x N, CV_64F (normalized)
  cv::Mat P1_cv, P2_cv;
};

Data make_data() {
  Data d;
  d.rig = naneye::recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  const CameraModel& cam = d.rig.left;
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u < cam.width(); ++u) {
      if (cam.in_domain(Eigen::Vector2d(u, v))) d.px.emplace_back(u, v);
    }
  }
  const std::size_t whole = d.px.size();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> U(0.0, cam.width() - 1.0), V(0.0, cam.height() - 1.0);
  while (d.px.size() < 2 * whole) {
    const Eigen::Vector2d p(U(rng), V(rng));
    if (cam.in_domain(p)) d.px.push_back(p);
  }
  d.px_cv = cv::Mat(static_cast<int>(d.px.size()), 1, CV_64FC2);
  for (std::size_t i = 0; i < d.px.size(); ++i) {
    d.px_cv.at<cv::Vec2d>(static_cast<int>(i)) = cv::Vec2d(d.px[i].x(), d.px[i].y());
  }
  cv::eigen2cv(cam.K(), d.K_cv);
  cv::eigen2cv(cam.distortion().opencv_order(), d.D_cv);

  const std::array<double, 6> depths = {15.0, 30.0, 50.0, 70.0, 95.0, 120.0};
  int k = 0;
  for (int v = 0; v < cam.height(); v += 2) {
    for (int u = 0; u < cam.width(); u += 2) {
      const naneye::recon::Undistorted und = cam.undistort(Eigen::Vector2d(u, v));
      if (!und.ok()) continue;
      const Eigen::Vector3d X =
          depths[static_cast<std::size_t>(k++) % depths.size()] * und.normalized.homogeneous();
      const Eigen::Vector2d pr = d.rig.right.project(d.rig.R * X + d.rig.T);
      if (pr.minCoeff() < 0.0 || pr.x() > d.rig.right.width() - 1.0 || pr.y() > d.rig.right.height() - 1.0)
        continue;
      d.X.push_back(X);
      d.pl.push_back(cam.project(X));
      d.pr.push_back(pr);
      d.xl.push_back(cam.undistort(d.pl.back()).normalized);
      d.xr.push_back(d.rig.right.undistort(pr).normalized);
    }
  }
  const int n = static_cast<int>(d.X.size());
  d.xl_cv = cv::Mat(2, n, CV_64F);
  d.xr_cv = cv::Mat(2, n, CV_64F);
  for (int i = 0; i < n; ++i) {
    d.xl_cv.at<double>(0, i) = d.xl[static_cast<std::size_t>(i)].x();
    d.xl_cv.at<double>(1, i) = d.xl[static_cast<std::size_t>(i)].y();
    d.xr_cv.at<double>(0, i) = d.xr[static_cast<std::size_t>(i)].x();
    d.xr_cv.at<double>(1, i) = d.xr[static_cast<std::size_t>(i)].y();
  }
  d.P1_cv = cv::Mat::eye(3, 4, CV_64F);
  d.P2_cv = cv::Mat(3, 4, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) d.P2_cv.at<double>(r, c) = d.rig.R(r, c);
    d.P2_cv.at<double>(r, 3) = d.rig.T(r);
  }
  return d;
}

const Data& data() {
  static const Data d = make_data();
  return d;
}

void set_per_point(benchmark::State& state, std::size_t n) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(n));
  state.counters["points"] = static_cast<double>(n);
  state.counters["time_per_pt"] = benchmark::Counter(
      static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

double roundtrip_px(const CameraModel& cam, const Eigen::Vector2d& px, const Eigen::Vector2d& xn) {
  return (cam.to_pixel(cam.distort(xn)) - px).norm();
}

// --- Undistortion ---------------------------------------------------------------------------

void BM_Undistort_Ours(benchmark::State& state) {
  const Data& d = data();
  std::vector<Eigen::Vector2d> out(d.px.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < d.px.size(); ++i) out[i] = d.rig.left.undistort(d.px[i]).normalized;
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  double worst = 0.0;
  for (std::size_t i = 0; i < d.px.size(); ++i)
    worst = std::max(worst, roundtrip_px(d.rig.left, d.px[i], out[i]));
  set_per_point(state, d.px.size());
  state.counters["max_err_px"] = worst;
}

void undistort_opencv(benchmark::State& state, const cv::TermCriteria* criteria) {
  const Data& d = data();
  cv::Mat out;
  for (auto _ : state) {
    if (criteria) {
      cv::undistortPoints(d.px_cv, out, d.K_cv, d.D_cv, cv::noArray(), cv::noArray(), *criteria);
    } else {
      cv::undistortPoints(d.px_cv, out, d.K_cv, d.D_cv);
    }
    benchmark::DoNotOptimize(out.data);
    benchmark::ClobberMemory();
  }
  double worst = 0.0;
  for (int i = 0; i < out.rows; ++i) {
    const cv::Vec2d x = out.at<cv::Vec2d>(i);
    worst = std::max(
        worst, roundtrip_px(d.rig.left, d.px[static_cast<std::size_t>(i)], Eigen::Vector2d(x[0], x[1])));
  }
  set_per_point(state, d.px.size());
  state.counters["max_err_px"] = worst;
}

void BM_Undistort_OpenCV_Default(benchmark::State& state) {
  undistort_opencv(state, nullptr);
}

void BM_Undistort_OpenCV_Count30_Eps1e6(benchmark::State& state) {
  const cv::TermCriteria c(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-6);
  undistort_opencv(state, &c);
}

void BM_Undistort_OpenCV_Count200_Eps1e9(benchmark::State& state) {
  const cv::TermCriteria c(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-9);
  undistort_opencv(state, &c);
}

// --- Triangulation on normalized coordinates (identical inputs for every method) -------------

template <typename F>
void triangulate_normalized(benchmark::State& state, F&& method) {
  const Data& d = data();
  std::vector<Eigen::Vector3d> out(d.X.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < d.X.size(); ++i) out[i] = method(d, i);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  double worst = 0.0;
  for (std::size_t i = 0; i < d.X.size(); ++i) worst = std::max(worst, (out[i] - d.X[i]).norm());
  set_per_point(state, d.X.size());
  state.counters["max_err_mm"] = worst;
}

void BM_Triangulate_DLT(benchmark::State& state) {
  triangulate_normalized(state, [](const Data& d, std::size_t i) {
    return naneye::recon::triangulate_dlt(d.rig, d.xl[i], d.xr[i]);
  });
}

void BM_Triangulate_Midpoint(benchmark::State& state) {
  triangulate_normalized(state, [](const Data& d, std::size_t i) {
    return naneye::recon::triangulate_midpoint(d.rig, d.xl[i], d.xr[i]);
  });
}

void BM_Triangulate_Niter2(benchmark::State& state) {
  triangulate_normalized(state, [](const Data& d, std::size_t i) {
    return naneye::recon::triangulate_niter2(d.rig, d.xl[i], d.xr[i]);
  });
}

void BM_Triangulate_Niter2_Refine(benchmark::State& state) {
  triangulate_normalized(state, [](const Data& d, std::size_t i) {
    const Eigen::Vector3d X0 = naneye::recon::triangulate_niter2(d.rig, d.xl[i], d.xr[i]);
    return naneye::recon::refine_reprojection(d.rig, X0, d.pl[i], d.pr[i]);
  });
}

void BM_Triangulate_OpenCV(benchmark::State& state) {
  const Data& d = data();
  cv::Mat Xh;
  for (auto _ : state) {
    cv::triangulatePoints(d.P1_cv, d.P2_cv, d.xl_cv, d.xr_cv, Xh);
    benchmark::DoNotOptimize(Xh.data);
    benchmark::ClobberMemory();
  }
  double worst = 0.0;
  for (int i = 0; i < Xh.cols; ++i) {
    const double w = Xh.at<double>(3, i);
    const Eigen::Vector3d X(Xh.at<double>(0, i) / w, Xh.at<double>(1, i) / w, Xh.at<double>(2, i) / w);
    worst = std::max(worst, (X - d.X[static_cast<std::size_t>(i)]).norm());
  }
  set_per_point(state, d.X.size());
  state.counters["max_err_mm"] = worst;
}

// --- The whole path from a raw pixel pair: undistort both, niter2, refine, depth sigma --------

void BM_Triangulate_RawPixels_Refined(benchmark::State& state) {
  const Data& d = data();
  std::vector<Eigen::Vector3d> out(d.X.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < d.X.size(); ++i) {
      out[i] = naneye::recon::triangulate(d.rig, d.pl[i], d.pr[i],
                                          naneye::recon::TriangulationMethod::refined, 0.2)
                   .X;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  double worst = 0.0;
  for (std::size_t i = 0; i < d.X.size(); ++i) worst = std::max(worst, (out[i] - d.X[i]).norm());
  set_per_point(state, d.X.size());
  state.counters["max_err_mm"] = worst;
}

// --- The depth sigma the calibration allows (geometry/calibration_uncertainty.hpp) ------------
// Per point, beside the triangulation above: what a calib_sigma_mm costs a sparse point or a
// /v1/depth/at answer, and what one per dense pixel would cost. The covariance is the marginals'
// diagonal (any covariance costs the same).

void BM_CalibrationDepthSigma(benchmark::State& state) {
  const Data& d = data();
  StereoRig rig = d.rig;
  rig.sigmas.covariance =
      naneye::recon::CalibrationUncertainty::assuming_independent_sigmas(rig)->covariance();
  const auto u = naneye::recon::CalibrationUncertainty::of(rig);
  std::vector<double> out(d.X.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < d.X.size(); ++i) out[i] = u->depth_sigma_mm(d.X[i]);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  set_per_point(state, d.X.size());
}

// The same per dense pixel from the table the dense path reads (calibration_sigma_table.hpp): each
// point looked up at its rounded left pixel. build_ms: the table's construction, once per rig.
void BM_CalibrationSigmaTable(benchmark::State& state) {
  const Data& d = data();
  StereoRig rig = d.rig;
  rig.sigmas.covariance =
      naneye::recon::CalibrationUncertainty::assuming_independent_sigmas(rig)->covariance();
  const auto t0 = std::chrono::steady_clock::now();
  const auto table = naneye::recon::CalibrationSigmaTable::of(rig);
  const double build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::vector<int> u(d.X.size()), v(d.X.size());
  for (std::size_t i = 0; i < d.X.size(); ++i) {
    u[i] = static_cast<int>(std::lround(d.pl[i].x()));
    v[i] = static_cast<int>(std::lround(d.pl[i].y()));
  }
  std::vector<float> out(d.X.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < d.X.size(); ++i) out[i] = table->depth_sigma_mm(u[i], v[i], d.X[i]);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  set_per_point(state, d.X.size());
  state.counters["build_ms"] = build_ms;
}

}  // namespace

BENCHMARK(BM_CalibrationDepthSigma)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CalibrationSigmaTable)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Undistort_Ours)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Undistort_OpenCV_Default)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Undistort_OpenCV_Count30_Eps1e6)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Undistort_OpenCV_Count200_Eps1e9)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_DLT)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_Midpoint)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_Niter2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_Niter2_Refine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_OpenCV)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulate_RawPixels_Refined)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
