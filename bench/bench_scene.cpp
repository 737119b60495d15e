// Sparse scene reconstruction, ours vs the OpenCV path a user would glue together (issue 14), on the
// same textured renders in one run, against their exact truth:
//   ours:   recon::scene::SparseReconstructor (docs/scene.md)
//   OpenCV: goodFeaturesToTrack + calcOpticalFlowPyrLK left -> right (from zero disparity) +
//           undistortPoints + triangulatePoints (P1 = [I|0], P2 = [R|T]), on the same luminance
//           (raw_to_luminance, min-max stretched to 8 bits for OpenCV).
// An outlier is a point whose left pixel sees no surface the right eye sees, or whose depth is off
// by more than 5 %. CPU time of this thread per pair, OpenCV limited to one thread.
//   build/bench/bench_scene [--seeds N] [--bayer]
#include <time.h>

#include <Eigen/Core>  // before opencv2/core/eigen.hpp

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <string>
#include <vector>

#include "naneye/recon/calibration_io.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/textured.hpp"

namespace {
using namespace naneye;

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Tally {
  std::vector<double> ms;
  long points = 0, outliers = 0, pairs = 0;
  double rel_err_sum = 0;  // |dZ| / Z over the inliers
  long inliers = 0;
  void add(double z, const cv::Mat& truth, double u, double v) {
    ++points;
    const int c = static_cast<int>(std::lround(u)), r = static_cast<int>(std::lround(v));
    const double zt = (c >= 0 && r >= 0 && c < truth.cols && r < truth.rows) ? truth.at<double>(r, c) : NAN;
    if (std::isnan(zt) || !(std::abs(z - zt) <= 0.05 * zt)) {
      ++outliers;
      return;
    }
    rel_err_sum += std::abs(z - zt) / zt;
    ++inliers;
  }
  double p50() {
    std::sort(ms.begin(), ms.end());
    return ms.empty() ? NAN : ms[ms.size() / 2];
  }
};

cv::Mat to8(const std::vector<float>& luma) {
  const cv::Mat f(250, 250, CV_32FC1, const_cast<float*>(luma.data()));
  cv::Mat out;
  cv::normalize(f, out, 0, 255, cv::NORM_MINMAX, CV_8U);
  return out;
}

void opencv_path(const recon::StereoRig& rig, const recon::scene::StereoLuma& luma, const cv::Mat& truth,
                 Tally& t) {
  const double t0 = thread_cpu_s();
  const cv::Mat l8 = to8(luma.left), r8 = to8(luma.right);
  std::vector<cv::Point2f> pl, pr;
  cv::goodFeaturesToTrack(l8, pl, 500, 0.01, 5);
  std::vector<unsigned char> status;
  std::vector<float> err;
  if (!pl.empty()) cv::calcOpticalFlowPyrLK(l8, r8, pl, pr, status, err, cv::Size(21, 21), 3);
  std::vector<cv::Point2f> gl, gr;
  for (std::size_t i = 0; i < pl.size(); ++i)
    if (status[i]) {
      gl.push_back(pl[i]);
      gr.push_back(pr[i]);
    }
  cv::Mat K1, K2, R, T;
  cv::eigen2cv(rig.left.K(), K1);
  cv::eigen2cv(rig.right.K(), K2);
  cv::eigen2cv(rig.R, R);
  cv::eigen2cv(rig.T, T);
  const auto& d1 = rig.left.distortion();
  const auto& d2 = rig.right.distortion();
  const cv::Mat D1 = (cv::Mat_<double>(1, 5) << d1.k1, d1.k2, d1.p1, d1.p2, d1.k3);
  const cv::Mat D2 = (cv::Mat_<double>(1, 5) << d2.k1, d2.k2, d2.p1, d2.p2, d2.k3);
  cv::Mat X;
  if (!gl.empty()) {
    std::vector<cv::Point2f> nl, nr;
    cv::undistortPoints(gl, nl, K1, D1);
    cv::undistortPoints(gr, nr, K2, D2);
    cv::Mat P1 = cv::Mat::eye(3, 4, CV_64F), P2(3, 4, CV_64F);
    R.copyTo(P2.colRange(0, 3));
    T.copyTo(P2.col(3));
    cv::triangulatePoints(P1, P2, nl, nr, X);
    X.convertTo(X, CV_64F);
  }
  t.ms.push_back(1e3 * (thread_cpu_s() - t0));
  ++t.pairs;
  for (std::size_t i = 0; i < gl.size(); ++i) {
    const double w = X.at<double>(3, static_cast<int>(i));
    t.add(X.at<double>(2, static_cast<int>(i)) / w, truth, gl[i].x, gl[i].y);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 3;
  bool bayer = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seeds") && i + 1 < argc) seeds = std::atoi(argv[++i]);
    if (!std::strcmp(argv[i], "--bayer")) bayer = true;
  }
  cv::setNumThreads(1);  // one core for both paths
  const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  sim::SensorSettings sensor;
  sensor.bayer = bayer;
  const sim::TexturedRenderer renderer(rig, sensor);
  recon::scene::SparseReconstructor ours(rig);
  recon::scene::SparseResult res;
  std::printf("bench_scene: %d renders per scene, %s, paper-d3 rig, one thread\n", seeds,
              bayer ? "GRBG Bayer" : "mono");
  std::printf("%-10s | %-44s | %-44s\n", "", "ours (sparse)", "OpenCV path");
  std::printf("%-10s | %7s %7s %9s %9s %7s | %7s %7s %9s %9s %7s\n", "scene", "p50 ms", "pts", "good",
              "outl %", "err %", "p50 ms", "pts", "good", "outl %", "err %");
  for (const auto& name : sim::textured_preset_names()) {
    Tally a, b;
    for (int s = 0; s < seeds; ++s) {
      sim::TexturedSceneSettings scene = *sim::textured_preset(name);
      scene.texture.seed += static_cast<std::uint64_t>(100 * s);
      sim::Rng rng(1000 + static_cast<std::uint64_t>(s));
      const sim::TexturedPair p = renderer.render(scene, rng);
      const auto lv = sim::raw_view(p.left, bayer), rv = sim::raw_view(p.right, bayer);
      const double t0 = thread_cpu_s();
      ours.reconstruct(lv, rv, res);
      a.ms.push_back(1e3 * (thread_cpu_s() - t0));
      ++a.pairs;
      for (const auto& q : res.points)
        if (q.valid()) a.add(q.X.z(), p.depth, q.left_px.x(), q.left_px.y());
      opencv_path(rig, ours.luma(), p.depth, b);
    }
    auto row = [](Tally& t) {
      std::printf(" %7.2f %7.0f %9.0f %8.2f%% %6.2f%%", t.p50(), double(t.points) / t.pairs,
                  double(t.points - t.outliers) / t.pairs, 100.0 * t.outliers / std::max(1L, t.points),
                  100.0 * t.rel_err_sum / std::max(1L, t.inliers));
    };
    std::printf("%-10s |", name.c_str());
    row(a);
    std::printf(" |");
    row(b);
    std::printf("\n");
  }
  std::printf(
      "pts/good: points per pair, all and within 5 %% of the truth where both eyes see it; outl: the "
      "rest; err: mean |dZ|/Z of the good ones\n");
  return 0;
}
