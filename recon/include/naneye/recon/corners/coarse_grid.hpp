#pragma once
// The full-search coarse grid of the corner detector (corners.hpp, docs/corners.md step 2): saddle
// points of the luminance (Hessian determinant, non-maximum suppression, a ring test that keeps
// only point-symmetric saddles), then a lattice grown over them in undistorted coordinates, where
// a plane's corners form a projective grid with nearly uniform steps. Its output only seeds the
// sub-pixel fit and the validation; it never decides alone that a board is there.
//
// Why our own instead of cv::findChessboardCorners: OpenCV's takes ~4 ms per eye here and
// allocates on every call; this one works in buffers sized once and takes a small fraction of that.
#include <complex>
#include <vector>

#include <Eigen/Core>

#include "naneye/recon/camera/camera_model.hpp"
#include "naneye/recon/corners/noise.hpp"
#include "naneye/recon/corners/refine.hpp"
#include "naneye/recon/pair/result.hpp"

namespace naneye::recon {

struct CoarseGridSettings {
  // Saddle map: a pixel is a candidate when -det(Hessian) is a 5x5 local maximum and at least this
  // share of the frame's strongest (a square law: 0.01 keeps corners down to 1/10 of the strongest
  // contrast, which covers vignetting and the side light).
  float min_relative_response = 0.01f;
  // ... and at least the response of a saddle of this contrast (white - black, DN) under a blur of
  // sigma 1 px: -det(H) = (C / (pi sigma_t^2))^2 at its centre, sigma_t^2 = 1 + 1 with our smoothing.
  // Without a board the strongest noise saddle is ~4 (DN / px^2)^2, this floor ~40 and the weakest
  // board corner of bench_corners ~600: a frame without a board stops here, before any ring test.
  float min_saddle_contrast_dn = 40.0f;
  // With the frame's noise model (find(..., noise)), the two DN floors above and below become
  // multiples of the noise sigma at the candidate's level. Smoothed noise has -det(H) up to ~0.45
  // sigma^2 over a 250 x 250 frame (var Hxx = 0.030 sigma^2, var Hxy = 0.0067 sigma^2 after the
  // binomial): a 6 sigma saddle responds with 0.91 sigma^2, twice that. The fit then requires the
  // same 6 sigma (CornerSettings::min_contrast_snr).
  float min_saddle_snr = 6.0f;
  // Ring test on a circle of this radius (pixels) around the candidate: the second angular harmonic
  // (four alternating quadrants) must exceed the first (an edge, an L-corner) by this ratio and
  // have at least this amplitude (DN).
  float ring_radius = 3.0f;
  float min_harmonic_ratio = 1.2f;
  float min_ring_amplitude_dn = 15.0f;
  // ... in noise sigmas: the amplitude's own noise is ~0.1 sigma (16 samples of the smoothed image,
  // sigma x 0.27 each), so 2 sigma is 20 of its standard deviations, and a 6 sigma saddle has an
  // amplitude of ~3.8 sigma (the square wave's second harmonic, 4 / pi of half the contrast).
  float min_ring_snr = 2.0f;
  int max_candidates = 256;
  // Lattice: a predicted neighbour is accepted within this share of the local step.
  float lattice_tolerance = 0.3f;
  int max_seeds = 12;
};

// One saddle candidate.
struct SaddleCandidate {
  Eigen::Vector2f px{0, 0};   // raw pixel, centres at integers
  Eigen::Vector2f und{0, 0};  // undistorted, normalized * fx (pixel-sized units)
  std::complex<float> phase;  // second angular harmonic: its sign flips between grid neighbours
  float response = 0;         // -det(Hessian) at the maximum
  bool usable = false;        // inside the camera model's domain
};

class CoarseGridFinder {
 public:
  // Tabulates the camera's undistortion (every kLutStep pixels) once; the image size is the camera's.
  explicit CoarseGridFinder(const CameraModel& cam, const CoarseGridSettings& settings = {});

  // Finds a rows x cols grid of saddles; on success writes rows * cols raw pixel positions to
  // `out` row-major in a consistent grid order (mirror and 180-degree turn not yet fixed: see
  // canonical_order). The pattern must fit the grown lattice at exactly one place: a larger board,
  // a grid with holes, or only part of the board in view gives false. Allocates nothing.
  // With `noise` (of the luminance), the contrast floors follow the frame's noise (settings).
  bool find(const LumaView& img, int rows, int cols, Eigen::Vector2f* out, const NoiseModel* noise = nullptr);
  // The next grid of the same frame, after the one the last find() / find_next() returned was refused
  // by the fit or the validation (a fine periodic texture of a photograph can form a lattice of its
  // own before the board's seeds are tried): the search goes on from the next seed, within the same
  // max_seeds. False when no other seed gives a grid, or one gives an uncertain placement.
  bool find_next(Eigen::Vector2f* out);

  // The lattice's undistortion: raw pixel -> normalized * fx, bilinear in a table of the exact
  // CameraModel::undistort where that is within kLutTolerancePx of it, else the exact inverse (next
  // to the fold). False beyond the model's fold or outside the image.
  bool undistort_px(const Eigen::Vector2f& px, Eigen::Vector2f& und) const;

  // The candidates of the last find() (diagnostics, tests).
  int candidate_count() const { return count_; }
  const SaddleCandidate* candidates() const { return cand_.data(); }

 private:
  // The largest pattern kMaxCorners allows is 1 x 64: a lattice of this side covers any growth from a
  // seed in its middle.
  static constexpr int kMaxSide = 2 * kMaxCorners + 3;
  static constexpr int kCandidateCapacity = 1024;
  static constexpr int kLutStep = 4;
  static constexpr float kLutTolerancePx = 0.02f;

  void saddle_map(const LumaView& img);
  void collect_candidates(const LumaView& img);
  bool collect_candidates(const LumaView& img, float boost);  // false: the buffer overflowed
  bool ring_test(const LumaView& img, SaddleCandidate& c) const;
  // 1: the pattern found at one place in the component and written to out; 0: no complete
  // placement (try another seed); -1: two placements or more saddles than the pattern has plus a
  // few false links (a larger board): nothing is certain.
  int grow(int seed, int rows, int cols, Eigen::Vector2f* out);
  bool seed_square(int seed, int& a, int& b, int& d) const;
  int nearest(const Eigen::Vector2f& at, float radius, int polarity_of, bool same_polarity) const;

  CoarseGridSettings s_;
  CameraModel cam_;
  int width_, height_;
  int lut_w_ = 0, lut_h_ = 0;
  std::vector<Eigen::Vector2f> lut_;   // undistorted (normalized * fx) at every kLutStep-th pixel
  std::vector<unsigned char> lut_ok_;  // per cell (its top-left node): interpolate, else exact
  std::vector<float> tmp_, smooth_, resp_;
  std::vector<SaddleCandidate> cand_;
  std::vector<int> order_, cell_of_;  // usable candidates by response; growth that took each (-1: none)
  std::vector<int> grid_;             // candidate per lattice cell (-1: empty), kSide x kSide
  int count_ = 0;
  int usable_ = 0, next_k_ = 0, tried_ = 0, rows_ = 0, cols_ = 0;  // the seed loop, resumable (find_next)
  int grid_count_ = -1;                // count_ before the returned grid's filled holes (-1: none returned)
  float peak_ = 0;                     // the strongest response of the last saddle_map
  int stamp_ = 0;                      // id of the current growth, marks its candidates in cell_of_
  const NoiseModel* noise_ = nullptr;  // of the current find()
  const LumaView* img_ = nullptr;      // of the current find()
};

}  // namespace naneye::recon
