#pragma once
// Dense scene depth on the left raw pixel grid (docs/scene.md). The contract the daemon
// and the CLI build on; the method lives in recon/scene/dense*.cpp:
// - every pixel of the left raw grid gets a depth Z (mm, left camera frame) and its 1-sigma, or NaN
//   in both where the result is not trusted (no texture, occluded, left-right inconsistent, outside
//   either model's domain, or the right eye cannot see it). Nothing beyond either fold is ever given.
// - rectification uses the exact model over the whole valid domain (no alpha-0 crop) and results are
//   mapped back to the raw grid, so a client indexes the map with the pixel it sees.
// - reconstruct() allocates nothing once warm: `out` keeps its capacity from pair to pair.
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/scene/dense_match.hpp"
#include "naneye/recon/scene/sparse.hpp"

namespace naneye::recon::scene {

struct DenseSettings {
  double z_min_mm = 5, z_max_mm = 150;  // mm; the depths searched (the scenes: 8-80 mm)
  // The rectified matcher (dense_match.hpp); its disparity band is set from z_min_mm / z_max_mm.
  MatcherSettings matcher;
  // Where the four rectified neighbours of a raw pixel differ by more than this, it sits on a depth
  // edge: no depth rather than a blend of two surfaces (px of disparity; the left-right tolerance).
  double max_neighbour_spread_px = 1.0;
  // The integer stage's band from the pair's own sparse points (reconstruct's `seed`): the SGM's work
  // is proportional to its band, and the whole 5-150 mm band is 48 px where a scene at 12-40 mm needs
  // ~14. The band spans the valid points' disparities widened by band_margin_px either side (px: the
  // parabola needs d - 1 and d + 1 inside, and the surface between two points may bulge beyond both
  // by ~1 px), rounded up to the SGM's 16. With fewer than min_band_points valid points the whole
  // band (too few to have seen every surface). A surface no point found whose disparity lies
  // outside the band gets no depth rather than a wrong one: a best on a narrowed edge is refused,
  // and the sub-pixel step's shift, residual and left-right tests catch a best inside it.
  // Off by default: the SGM's left-right check is weaker in a narrower band (its right view has
  // fewer wrong places to land), so on realistic data the band also admits pixels the whole band
  // refused, ~3-4 % of them wrong (Middlebury's Aloe: bad-2.0 0.81 -> 1.22 %, coverage +12 %; the
  // real-sensor renders: bad-5 +0.03-0.3 points), for 7.6 % fewer instructions (docs/scene.md,
  // "The band from the sparse points"). Exactness first; on for speed where that trade suits.
  bool band_from_sparse = false;
  double band_margin_px = 2.0;
  int min_band_points = 24;
};

struct DepthMap {
  static constexpr float kNone = std::numeric_limits<float>::quiet_NaN();
  int width = 0, height = 0;    // the left raw grid
  std::vector<float> z_mm;      // row-major, width * height; NaN = no depth
  std::vector<float> sigma_mm;  // 1-sigma of z_mm from the match (noise, texture); NaN where z_mm is NaN
  // The depth sigma the calibration's covariance allows at each depth (CalibrationSigmaTable):
  // systematic, common to the whole map (one calibration), so it does not shrink when depths are
  // averaged, unlike sigma_mm. NaN where z_mm is NaN and everywhere when the calibration carries no
  // covariance (the paper's files: marginal sigmas only, docs/calibration.md).
  std::vector<float> calib_sigma_mm;
  int valid_count = 0;     // pixels with a depth
  int visible_count = 0;   // pixels both eyes can see (inside both domains, in both images)
  double valid_share = 0;  // valid_count / visible_count (0 when nothing is visible)
  double median_mm = std::numeric_limits<double>::quiet_NaN();              // of the valid depths
  double calib_sigma_median_mm = std::numeric_limits<double>::quiet_NaN();  // of calib_sigma_mm's valid ones
  bool empty() const { return valid_count == 0; }
  float z_at(int u, int v) const { return z_mm[static_cast<std::size_t>(v) * width + u]; }
  float sigma_at(int u, int v) const { return sigma_mm[static_cast<std::size_t>(v) * width + u]; }
  float calib_sigma_at(int u, int v) const { return calib_sigma_mm[static_cast<std::size_t>(v) * width + u]; }
};

class DenseReconstructor {
 public:
  explicit DenseReconstructor(const StereoRig& rig, const DenseSettings& s = {});
  ~DenseReconstructor();
  DenseReconstructor(DenseReconstructor&&) noexcept;
  DenseReconstructor& operator=(DenseReconstructor&&) noexcept;
  // One pair from luminance already computed (SparseReconstructor::load_luma / luma()), so that the
  // sparse and dense paths share one demosaic and one noise estimate.
  // `seed`: this pair's sparse result (DenseSettings::band_from_sparse), or none: the whole band.
  void reconstruct(const StereoLuma& luma, DepthMap& out, const SparseResult* seed = nullptr);
  const StereoRig& rig() const;
  // Why the last pair's rectified pixels have no disparity (dense_match.hpp).
  const MatchCounts& match_counts() const;
  const RectifiedMatcher& matcher() const;
  const DenseSettings& settings() const;

 private:
  struct Impl;  // rectification maps, cost volume, scratch: sized once in the constructor
  std::unique_ptr<Impl> impl_;
};

}  // namespace naneye::recon::scene
