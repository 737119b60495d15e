// Our semi-global matcher (sgm.hpp): the per-row driver, the winner-take-all with its parabola,
// and the left-right check; the row kernels are in sgm_simd.cpp.
#include "sgm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace naneye::recon::scene {
namespace {
constexpr int kCensusBits = 24;  // 5 x 5 window less its centre (sgm_simd.hpp)
constexpr int kBlock = 9;        // the cost's 3 x 3 block
constexpr int kPaths = 5;
}  // namespace

Sgm::Sgm(int width, int height, const SgmSettings& s)
    : s_(s), w_(width), h_(height), min_(s.min_disparity), D_(s.num_disparities), isa_(sgm_simd::best_isa()) {
  CV_Assert(s.min_disparity >= 0 && D_ > 0 && D_ % 16 == 0 && s.p1 >= 0 && s.p2 >= s.p1);
  // Every path value is at most C + P2 (Eq. 13 subtracts the predecessor's minimum), so S, the sum
  // of five, stays below the pads and int16 holds it.
  CV_Assert(kPaths * (kCensusBits * kBlock + s.p2) < sgm_simd::kPad);
  const auto w = static_cast<std::size_t>(w_), D = static_cast<std::size_t>(D_), Ds = D + 2;
  lo_.assign(static_cast<std::size_t>(h_), 0);
  hi_.assign(static_cast<std::size_t>(h_), 0);
  cl_.assign(w, 0);
  cr_.assign(w, 0);
  crev_lo_.assign(w, 0);
  crev_hi_.assign(w, 0);
  ham_.assign(w * D, 0);
  ring_.assign(3 * w * D, 0);
  cost_.assign(w * D, 0);
  sum_.assign(w * D, 0);
  // The path blocks' pads (0 and D + 1) keep kPad for good: the kernels write only 1 .. D.
  paths_.assign(6 * w * Ds, sgm_simd::kPad);
  path_min_.assign(6 * w, 0);
  horiz_.assign(4 * Ds, sgm_simd::kPad);
  start_.assign(Ds, 0);
  start_.front() = start_.back() = sgm_simd::kPad;
  rcost_.assign(w, 0);
  rdisp_.assign(w, 0);
  best_.assign(w, 0);
}

void Sgm::set_band(int min_disparity, int num_disparities) {
  CV_Assert(num_disparities > 0 && num_disparities % 16 == 0 && min_disparity >= s_.min_disparity &&
            min_disparity + num_disparities <= s_.min_disparity + s_.num_disparities);
  min_ = min_disparity;
  if (num_disparities == D_) return;
  D_ = num_disparities;
  // The path blocks' pads move with the block length (D + 2): lay them out again.
  std::fill(paths_.begin(), paths_.end(), sgm_simd::kPad);
  std::fill(horiz_.begin(), horiz_.end(), sgm_simd::kPad);
  std::fill(start_.begin(), start_.end(), std::int16_t{0});
  start_[0] = start_[static_cast<std::size_t>(D_) + 1] = sgm_simd::kPad;
}

// The 3-column Hamming sums of row k into its ring slot, over the columns its neighbour rows match
// (row k enters the block of rows k - 1 .. k + 1).
void Sgm::cost_row(const cv::Mat& left, const cv::Mat& right, int k) {
  const std::size_t D = static_cast<std::size_t>(D_);
  ring_row_[k % 3] = k;
  int u0 = w_, u1 = 0;
  for (int j = std::max(0, k - 1); j <= std::min(h_ - 1, k + 1); ++j)
    if (range_lo(j) < range_hi(j)) {
      u0 = std::min(u0, range_lo(j));
      u1 = std::max(u1, range_hi(j));
    }
  if (u0 >= u1) return;
  // Hamming distances one column either side (u0 >= min + D, so u0 - 1 still has the whole band).
  const int h0 = u0 - 1, h1 = std::min(w_, u1 + 1);
  const int dmin = min_;
  const int r0 = h0 - dmin - D_ + 1, r1 = h1 - dmin;  // the right columns they reach, >= 0
  sgm_simd::census_row(isa_, left.ptr<float>(), left.step1(), w_, h_, k, h0, h1, cl_.data());
  sgm_simd::census_row(isa_, right.ptr<float>(), right.step1(), w_, h_, k, r0, r1, cr_.data());
  for (int j = r0; j < r1; ++j) {
    const std::uint32_t c = cr_[static_cast<std::size_t>(j)];
    crev_lo_[static_cast<std::size_t>(w_ - 1 - j)] = static_cast<std::uint16_t>(c & 0xffffu);
    crev_hi_[static_cast<std::size_t>(w_ - 1 - j)] = static_cast<std::uint16_t>(c >> 16);
  }
  sgm_simd::hamming_row(isa_, cl_.data(), crev_lo_.data(), crev_hi_.data(), w_, dmin, D_, h0, h1,
                        ham_.data());
  sgm_simd::hsum3_row(isa_, ham_.data(), D_, h0, h1, u0, u1,
                      ring_.data() + static_cast<std::size_t>(k % 3) * w_ * D);
}

void Sgm::run(const cv::Mat& left, const cv::Mat& right, const int* lo, const int* hi, cv::Mat& disparity) {
  CV_Assert(left.type() == CV_32FC1 && right.type() == CV_32FC1 && left.size() == right.size() &&
            left.cols == w_ && left.rows == h_ && disparity.type() == CV_32FC1 &&
            disparity.size() == left.size());
  const std::size_t W = static_cast<std::size_t>(w_), D = static_cast<std::size_t>(D_), Ds = D + 2;
  const int dmin = min_;
  // A winner on an edge the band was narrowed at: the cost may fall on beyond it (set_band).
  const bool low_cut = min_ > s_.min_disparity;
  const bool high_cut = min_ + D_ < s_.min_disparity + s_.num_disparities;
  for (int y = 0; y < h_; ++y) {
    const auto k = static_cast<std::size_t>(y);
    lo_[k] = std::max(lo[y], first_column());
    hi_[k] = std::min(hi[y], w_);
    if (lo_[k] >= hi_[k]) lo_[k] = hi_[k] = 0;
  }
  std::fill(std::begin(ring_row_), std::end(ring_row_), -1);
  lr_refused_ = edge_refused_ = 0;
  int prev_lo = 0, prev_hi = 0;
  for (int y = 0; y < h_; ++y) {
    float* out = disparity.ptr<float>(y);
    std::fill(out, out + w_, std::numeric_limits<float>::quiet_NaN());
    const int a = range_lo(y), b = range_hi(y);
    if (a >= b) {
      prev_lo = prev_hi = 0;  // the vertical paths restart below a row without data
      continue;
    }
    // C: the 3 x 3 block sum of Hamming distances (the rows beyond the image repeat this one).
    const int rows[3] = {std::max(0, y - 1), y, std::min(h_ - 1, y + 1)};
    for (int r : rows)
      if (ring_row_[r % 3] != r) cost_row(left, right, r);
    auto ring = [&](int r) { return ring_.data() + static_cast<std::size_t>(r % 3) * W * D; };
    sgm_simd::add3_row(isa_, ring(rows[0]), ring(rows[1]), ring(rows[2]), D_, a, b, cost_.data());

    // Eq. 13 along the five paths, S = their sum (Eq. 14).
    sgm_simd::PathRow pr{};
    const std::size_t cur = static_cast<std::size_t>(y & 1), prev = cur ^ 1;
    for (std::size_t j = 0; j < 3; ++j) {
      pr.prev[j] = paths_.data() + (prev * 3 + j) * W * Ds;
      pr.prev_min[j] = path_min_.data() + (prev * 3 + j) * W;
      pr.cur[j] = paths_.data() + (cur * 3 + j) * W * Ds;
      pr.cur_min[j] = path_min_.data() + (cur * 3 + j) * W;
    }
    pr.prev_lo = prev_lo;
    pr.prev_hi = prev_hi;
    for (std::size_t j = 0; j < 2; ++j) {
      pr.horiz[j] = horiz_.data() + j * Ds;
      pr.horiz_back[j] = horiz_.data() + (2 + j) * Ds;
    }
    pr.start = start_.data();
    pr.cost = cost_.data();
    pr.sum = sum_.data();
    pr.lo = a;
    pr.hi = b;
    pr.D = D_;
    pr.p1 = static_cast<std::int16_t>(s_.p1);
    pr.p2 = static_cast<std::int16_t>(s_.p2);
    sgm_simd::aggregate_row(isa_, pr);
    prev_lo = a;
    prev_hi = b;

    // Winner-take-all on S, both views (Hirschmueller 2008, Sec. 3.4: D_m(x_r) = argmin_d S(x_r + d, d)
    // from the same S). Ties keep the smallest disparity, as cv::StereoSGBM does.
    const int r0 = a - dmin - D_ + 1, r1 = b - dmin;  // the right pixels the row reaches
    const std::size_t j0 = static_cast<std::size_t>(w_ - r1), j1 = static_cast<std::size_t>(w_ - r0);
    std::fill(rcost_.begin() + j0, rcost_.begin() + j1, std::numeric_limits<std::int16_t>::max());
    std::fill(rdisp_.begin() + j0, rdisp_.begin() + j1, static_cast<std::int16_t>(-1));
    sgm_simd::wta_row(isa_, sum_.data(), D_, dmin, w_, a, b, best_.data(), rcost_.data(), rdisp_.data());
    for (int x = a; x < b; ++x) {
      const std::int16_t* s = sum_.data() + static_cast<std::size_t>(x) * D;
      const int d = best_[static_cast<std::size_t>(x)];
      if ((low_cut && d == 0) || (high_cut && d == D_ - 1)) {
        out[x] = std::numeric_limits<float>::infinity();
        ++edge_refused_;
        continue;
      }
      float v = static_cast<float>(dmin + d);
      if (d > 0 && d < D_ - 1) {
        // The parabola through S at d - 1, d, d + 1 (its vertex; |offset| <= 1/2 at a minimum).
        const int den = std::max(1, s[d - 1] + s[d + 1] - 2 * s[d]);
        v += static_cast<float>(s[d - 1] - s[d + 1]) / static_cast<float>(2 * den);
      }
      out[x] = v;
    }
    // Left-right check, cv::StereoSGBM's rule (sgm.hpp): both roundings of v disagree with a right
    // disparity that exists.
    auto disagrees = [&](int xr, int d) {
      if (xr < r0 || xr >= r1) return false;
      const std::int16_t dr = rdisp_[static_cast<std::size_t>(w_ - 1 - xr)];
      return dr >= dmin && std::abs(dr - d) > s_.lr_max_diff;
    };
    for (int x = a; x < b; ++x) {
      if (!std::isfinite(out[x])) continue;
      const int d0 = static_cast<int>(std::floor(out[x])), d1 = static_cast<int>(std::ceil(out[x]));
      if (disagrees(x - d0, d0) && disagrees(x - d1, d1)) {
        out[x] = std::numeric_limits<float>::quiet_NaN();
        ++lr_refused_;
      }
    }
  }
}

}  // namespace naneye::recon::scene
