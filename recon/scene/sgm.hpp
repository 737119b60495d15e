#pragma once
// Our semi-global matcher (Hirschmueller, "Stereo processing by semiglobal matching and mutual
// information", IEEE PAMI 30(2), 2008), the dense path's integer stage (dense_match.cpp); it
// replaces cv::StereoSGBM, which allocated its buffers on every call (docs/scene.md).
//
// - Cost: the Hamming distance between 5 x 5 census transforms (Zabih & Woodfill 1994), summed over
//   a 3 x 3 block: 0 .. 9 x 24 bits. Census compares each pixel with its window's centre only, so
//   it is blind to a gain and an offset between the eyes (the Bayer channel gains, Aloe's exposure)
//   and needs no 8-bit quantisation of the float images; Hirschmueller & Scharstein (PAMI 31(9),
//   2009) found it the most robust of the costs they compared under SGM. P1 and P2 are in the same
//   unit, bits of the block's summed distance.
// - Paths: five, all in one top-to-bottom sweep (OpenCV's MODE_SGBM has the same five): left to
//   right, top-left, top, top-right, and right to left. Every path's predecessor lies on this row or
//   the one above, so a row's sum S is final once the row is done: the disparities of both views
//   are taken from it row by row, and the cost volume is never stored (only a few rows of w x D).
//   The 3-way variant the path had before (cv::StereoSGBM MODE_SGBM_3WAY: left, right, top) lacks
//   the diagonals; the eight-path full version needs a second sweep and the whole volume.
// - Columns: per row only [span_lo, span_hi) (the left data) from min + D on (as cv::StereoSGBM:
//   left of that the band leaves the right image); outside them nothing is read or written.
// - Output: the winner-take-all disparity with a parabola through S at d - 1, d, d + 1, and a
//   left-right check on the same S (the right view's disparity at x_r is the argmin of S along the
//   diagonal x = x_r + d), with cv::StereoSGBM's rule: a left disparity v fails when the right
//   disparity at x - floor(v) and at x - ceil(v) both exist and differ from those roundings by more
//   than lr_max_diff.
// - Band: the settings' band sizes the buffers; a run may search a narrower one (set_band: the dense
//   path narrows it to the disparities the pair's sparse points found, dense.hpp). Its work is
//   proportional to the band's width.
// All buffers are sized in the constructor: run() allocates nothing. No threads.
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "sgm_simd.hpp"

namespace naneye::recon::scene {

struct SgmSettings {
  int min_disparity = 0;     // px, >= 0
  int num_disparities = 48;  // px, a multiple of 16 (the kernels' vector width)
  int p1 = 2 * 9;            // bits of the 3 x 3 block's census distance (see MatcherSettings)
  int p2 = 8 * 9;
  int lr_max_diff = 0;  // px; see above (0: the right disparity equals one of the roundings)
};

class Sgm {
 public:
  Sgm(int width, int height, const SgmSettings& s);
  // left, right: CV_32FC1 (width x height); lo[y], hi[y]: each row's columns of left data.
  // disparity (CV_32FC1, width x height, allocated by the caller): the sub-pixel disparity, NaN where
  // there is none (outside the columns matched, or refused by the left-right check).
  void run(const cv::Mat& left, const cv::Mat& right, const int* lo, const int* hi, cv::Mat& disparity);
  // The first column with the whole band inside the right image: min + D.
  int first_column() const { return min_ + D_; }
  // The band of the next runs: [min_disparity, min_disparity + num_disparities) inside the
  // settings' (the buffers' capacity), num a multiple of 16; the settings' band when never called.
  // A winner on an edge the band was narrowed at is refused (+infinity in disparity): the cost may
  // fall on beyond it, so that is no minimum (band_edge_refused()). Allocates nothing.
  void set_band(int min_disparity, int num_disparities);
  int band_min() const { return min_; }
  int band_size() const { return D_; }
  int band_edge_refused() const { return edge_refused_; }  // last run's
  int left_right_refused() const { return lr_refused_; }   // last run's
  const SgmSettings& settings() const { return s_; }
  void set_isa(sgm_simd::Isa isa) { isa_ = isa; }  // the tests compare the builds

 private:
  void cost_row(const cv::Mat& left, const cv::Mat& right, int k);
  int range_lo(int y) const { return lo_[static_cast<std::size_t>(y)]; }
  int range_hi(int y) const { return hi_[static_cast<std::size_t>(y)]; }

  SgmSettings s_;
  int w_, h_;
  int min_, D_;  // the band run (set_band), inside the settings' band
  sgm_simd::Isa isa_;
  std::vector<int> lo_, hi_;                      // per row: the columns matched (empty: lo = hi)
  std::vector<std::uint32_t> cl_, cr_;            // one row's census, left and right
  std::vector<std::uint16_t> crev_lo_, crev_hi_;  // the right one reversed, low 16 and high 8 bits
  std::vector<std::int16_t> ham_;                 // one row's Hamming distances, w x D
  std::vector<std::int16_t> ring_;                // three rows of 3-column sums, 3 x w x D
  int ring_row_[3] = {-1, -1, -1};                // the row each ring slot holds
  std::vector<std::int16_t> cost_, sum_;          // this row's C and S, w x D
  std::vector<std::int16_t> paths_;               // 2 x 3 rows of path values (w x (D + 2)), this and above
  std::vector<std::int16_t> path_min_;            // their minima, 2 x 3 x w
  std::vector<std::int16_t> horiz_;               // 4 blocks of D + 2: the two horizontal paths
  std::vector<std::int16_t> start_;               // a zero block with padded ends
  std::vector<std::int16_t> best_;                // one row's winner, d - min
  std::vector<std::int16_t> rcost_, rdisp_;       // the right view's best S and disparity, one row, reversed
  int lr_refused_ = 0, edge_refused_ = 0;
};

}  // namespace naneye::recon::scene
