#pragma once
// bench_scene's tallies against the renders' truth: sparse points (Tally), dense maps (DenseTally),
// both dense paths on their common pixels (CommonTally), and the digests that show a speed change
// left every result's bits as they were (Digest).
#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "naneye/recon/scene/sparse.hpp"

namespace naneye::bench_scene {

// FNV-1a (64 bit) over raw bytes, chained: a change in any bit of any result changes the digest.
struct Digest {
  std::uint64_t h = 14695981039346656037ull;
  void add(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class T>
  void add(const T& v) {
    add(&v, sizeof v);
  }
};

void digest_sparse(Digest& d, const recon::scene::SparseResult& r) {
  for (const auto& q : r.points) {
    d.add(static_cast<int>(q.status));
    d.add(q.id);
    d.add(q.left_px.data(), 2 * sizeof(double));
    d.add(q.right_px.data(), 2 * sizeof(double));
    d.add(q.X.data(), 3 * sizeof(double));
    d.add(q.depth_sigma_mm);
  }
}

struct Tally {
  std::vector<double> ms;
  long points = 0, outliers = 0, pairs = 0;
  double rel_err_sum = 0;  // |dZ| / Z over the inliers
  long inliers = 0;
  double z2_sum = 0;  // (dZ / sigma)^2 over the inliers given a sigma
  long z_count = 0;
  // Returns (z - truth) / sigma for a good point given a sigma, else NaN.
  double add(double z, const cv::Mat& truth, double u, double v, double sigma = NAN) {
    ++points;
    const int c = static_cast<int>(std::lround(u)), r = static_cast<int>(std::lround(v));
    const double zt = (c >= 0 && r >= 0 && c < truth.cols && r < truth.rows) ? truth.at<double>(r, c) : NAN;
    if (std::isnan(zt) || !(std::abs(z - zt) <= 0.05 * zt)) {
      ++outliers;
      return NAN;
    }
    rel_err_sum += std::abs(z - zt) / zt;
    ++inliers;
    if (!(sigma > 0)) return NAN;
    const double e = (z - zt) / sigma;
    z2_sum += e * e;
    ++z_count;
    return e;
  }
  double p50() {
    std::sort(ms.begin(), ms.end());
    return ms.empty() ? NAN : ms[ms.size() / 2];
  }
};

// Dense figures of a depth map on the left raw grid against the truth (NaN = none in both).
struct DenseTally {
  std::vector<double> ms;
  std::string radii;  // the dense matcher's window radius per pair, px
  std::string bands;  // the SGM's disparity band per pair, first + count, px
  long truth = 0, covered = 0, unseen = 0, valid = 0, bad5 = 0;
  double rel_sum = 0;
  void add(const cv::Mat& z, const cv::Mat& truth_z) {
    for (int r = 0; r < truth_z.rows; ++r)
      for (int c = 0; c < truth_z.cols; ++c) {
        const double zt = truth_z.at<double>(r, c), zz = z.at<float>(r, c);
        truth += std::isfinite(zt);
        if (!std::isfinite(zz)) continue;
        ++valid;
        if (!std::isfinite(zt)) {
          ++unseen;
          continue;
        }
        ++covered;
        rel_sum += std::abs(zz - zt) / zt;
        bad5 += std::abs(zz - zt) > 0.05 * zt;
      }
  }
  double p50() {
    std::sort(ms.begin(), ms.end());
    return ms.empty() ? NAN : ms[ms.size() / 2];
  }
};

// Both dense maps on the pixels both give a depth where the truth has one: the same pixels, so that
// the OpenCV path's central crop (its alpha 0 rectification) does not flatter or harm either.
struct CommonTally {
  long pix = 0, bad_ours = 0, bad_cv = 0;
  double rel_ours = 0, rel_cv = 0;
  void add(const cv::Mat& ours, const cv::Mat& theirs, const cv::Mat& truth_z) {
    for (int r = 0; r < truth_z.rows; ++r)
      for (int c = 0; c < truth_z.cols; ++c) {
        const double zt = truth_z.at<double>(r, c), a = ours.at<float>(r, c), b = theirs.at<float>(r, c);
        if (!std::isfinite(zt) || !std::isfinite(a) || !std::isfinite(b)) continue;
        ++pix;
        rel_ours += std::abs(a - zt) / zt;
        rel_cv += std::abs(b - zt) / zt;
        bad_ours += std::abs(a - zt) > 0.05 * zt;
        bad_cv += std::abs(b - zt) > 0.05 * zt;
      }
  }
};

}  // namespace naneye::bench_scene
