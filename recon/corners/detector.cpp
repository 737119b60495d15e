// CornerDetector: the frame-level flow (luminance, tracking or full search, validation) and the
// ordering of a found grid; the per-corner refinement is in corners/refine_grid.cpp.
#include <algorithm>
#include <cmath>

#include "naneye/base/enum_table.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/grid.hpp"
#include "naneye/recon/corners/refine.hpp"
#include "plane.hpp"

namespace naneye::recon {

namespace {
double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Sum of the grid's outer edges along columns and along rows.
void grid_axes(const CornerResult& r, Eigen::Vector2d& col_dir, Eigen::Vector2d& row_dir) {
  const int R = r.rows - 1, C = r.cols - 1;
  col_dir = (r.at(0, C).px - r.at(0, 0).px) + (r.at(R, C).px - r.at(R, 0).px);
  row_dir = (r.at(R, 0).px - r.at(0, 0).px) + (r.at(R, C).px - r.at(0, C).px);
}

void renumber(CornerResult& r) {
  for (int i = 0; i < r.count; ++i) {
    r.corners[static_cast<std::size_t>(i)].row = i / r.cols;
    r.corners[static_cast<std::size_t>(i)].col = i % r.cols;
  }
}
}  // namespace

namespace {
constexpr base::EnumTable<CornerFailure, 9> kCornerFailureNames{
    {{CornerFailure::none, "none"},
     {CornerFailure::bad_input, "bad_input"},
     {CornerFailure::no_grid, "no_grid"},
     {CornerFailure::fit_failed, "fit_failed"},
     {CornerFailure::fit_rejected, "fit_rejected"},
     {CornerFailure::low_contrast, "low_contrast"},
     {CornerFailure::polarity, "polarity"},
     {CornerFailure::not_planar, "not_planar"},
     {CornerFailure::track_moved, "track_moved"}}};
}  // namespace

const char* to_string(CornerFailure f) {
  return base::enum_name(kCornerFailureNames, f);
}

void canonical_order(CornerResult& r) {
  if (r.count != r.rows * r.cols || r.rows < 2 || r.cols < 2) return;
  Eigen::Vector2d col_dir, row_dir;
  grid_axes(r, col_dir, row_dir);
  // Seen from the front, a board frame (u along columns, v along rows, z into the board) is
  // right-handed only when u x v > 0 in the image (y down); OpenCV may return the mirrored order.
  if (cross2(col_dir, row_dir) < 0) {
    for (int row = 0; row < r.rows / 2; ++row) {
      for (int col = 0; col < r.cols; ++col) {
        std::swap(r.corners[static_cast<std::size_t>(row * r.cols + col)],
                  r.corners[static_cast<std::size_t>((r.rows - 1 - row) * r.cols + col)]);
      }
    }
    grid_axes(r, col_dir, row_dir);
  }
  const bool horizontal = std::abs(col_dir.x()) >= std::abs(col_dir.y());
  const double along = horizontal ? col_dir.x() : col_dir.y();
  if (along < 0) std::reverse(r.corners.begin(), r.corners.begin() + r.count);
  renumber(r);
}

namespace {

// The next pyramid level exists while its image is at least this many pixels on its shorter side:
// the detector's pixel scales (saddle ring 3 px, fit windows <= 7 px, blur bounds) are made for this
// sensor's 250 x 250 frames, where a board in view has squares of ~4-40 px; a larger image of the
// same board has proportionally larger squares, and at half its size they are back in that range.
constexpr int kMinLevelSide = 240;

// The same lens at half the resolution: level pixel x' = (x + 0.5) / 2 - 0.5, so K' = S K with
// S = diag(1/2, 1/2, 1) and the principal point shifted by -1/4; the distortion (in normalised
// coordinates) is the same.
CameraModel half_camera(const CameraModel& cam) {
  Eigen::Matrix3d k = cam.K();
  k.row(0) *= 0.5;
  k.row(1) *= 0.5;
  k(0, 2) -= 0.25;
  k(1, 2) -= 0.25;
  return CameraModel(k, cam.distortion(), cam.width() / 2, cam.height() / 2);
}

}  // namespace

CornerDetector::CornerDetector(const CameraModel& camera, const CornerSettings& settings)
    : camera_(camera),
      settings_(settings),
      width_(camera.width()),
      height_(camera.height()),
      coarse_finder_(camera, settings.coarse) {
  luma_.resize(static_cast<std::size_t>(width_) * height_);
  scratch_.resize(luma_.size());
  clipped_.resize(luma_.size());
  coarse_.resize(kMaxCorners);
  gray8_.resize(luma_.size());
  map_ = std::make_shared<const UndistortMap>(camera_);
  work_.resize(1);
  work_.front().use_avx2 = work_.front().use_avx2 && settings_.allow_avx2;
  z_reject_ = upper_normal_quantile(settings_.residual_false_reject);
  if (std::min(width_, height_) / 2 >= kMinLevelSide) {
    half_.emplace_back(half_camera(camera_), settings_);
    half_raw_.resize(static_cast<std::size_t>(width_ / 2) * (height_ / 2));
  }
}

bool CornerDetector::detect(const RawImageView& image, const CornerResult* previous, CornerResult& out) {
  if (!half_.empty() && previous && previous->found && from_half_ && image.width == width_ &&
      image.height == height_ && image.data) {
    if (detect_half(image, true, out)) return true;
    previous = nullptr;  // the board left the next level: this one searches afresh
  }
  from_half_ = false;
  if (detect_here(image, previous, out) || half_.empty() || failure_ == CornerFailure::bad_input)
    return out.found;
  // What this level saw is the reason given when the next level finds nothing either.
  const CornerFailure failure = failure_;
  const CornerRejection rejection = rejection_;
  if (detect_half(image, false, out)) return true;
  failure_ = failure;
  rejection_ = rejection;
  return false;
}

bool CornerDetector::detect_half(const RawImageView& image, bool track_previous, CornerResult& out) {
  // 2 x 2 binning: a mono image of the scene also from a Bayer mosaic (each block holds one R, two G
  // and one B site: the luminance's own 1/4, 1/2, 1/4, whatever the white balance), with a quarter of
  // the noise variance. A block with a clipped pixel is no measure of the light: it reads as clipped.
  const int w = width_ / 2, h = height_ / 2;
  constexpr auto kClipRaw = static_cast<unsigned>(kClipDn);
  for (int r = 0; r < h; ++r) {
    const std::uint16_t* p = image.data + static_cast<std::ptrdiff_t>(2 * r) * image.stride;
    std::uint16_t* q = half_raw_.data() + static_cast<std::size_t>(r) * w;
    for (int c = 0; c < w; ++c) {
      const unsigned a = p[2 * c], b = p[2 * c + 1], d = p[image.stride + 2 * c],
                     e = p[image.stride + 2 * c + 1];
      const bool clipped = std::max({a, b, d, e}) >= kClipRaw;
      q[c] = static_cast<std::uint16_t>(clipped ? 1023u : (a + b + d + e + 2) / 4);
    }
  }
  const RawImageView view{half_raw_.data(),
                          w,
                          h,
                          w,
                          PixelLayout::mono,
                          (image.ignore_last_cols + 1) / 2,
                          (image.ignore_edge_rows + 1) / 2};
  std::swap(half_previous_, half_result_);
  from_half_ = half_.front().detect(view, track_previous ? &half_previous_ : nullptr, half_result_);
  if (!from_half_) return false;
  // Level pixel x' = (x + 0.5) / 2 - 0.5 (centres at integers): x = 2 x' + 0.5. Not fitted again on
  // this level's pixels: on OpenCV's photographs enlarged 2x, fits here (windows of <= 7 px on edges
  // blurred to ~2 px) passed validation but were further from cornerSubPix (0.163 against 0.139 px
  // RMS, 242 against 126 corners beyond 0.3 px) than the next level's, scaled.
  out = half_result_;
  for (int i = 0; i < out.count; ++i) {
    Corner& k = out.corners[static_cast<std::size_t>(i)];
    k.px = 2.0 * k.px + Eigen::Vector2d(0.5, 0.5);
    k.sigma_px *= 2.0;
    k.position_se_px *= 2.0;
    k.shading.gx *= 0.5;
    k.shading.gy *= 0.5;
    k.shading.hx *= 0.5;
    k.shading.hy *= 0.5;
  }
  failure_ = CornerFailure::none;
  return true;
}

bool CornerDetector::detect_here(const RawImageView& image, const CornerResult* previous, CornerResult& out) {
  out.found = false;
  out.tracked = false;
  out.count = 0;
  out.rows = settings_.board.rows;
  out.cols = settings_.board.cols;
  failure_ = CornerFailure::none;
  if (image.width != width_ || image.height != height_ || !image.data ||
      settings_.board.rows * settings_.board.cols > kMaxCorners) {
    failure_ = CornerFailure::bad_input;
    return false;
  }
  row_begin_ = image.ignore_edge_rows;
  row_end_ = height_ - image.ignore_edge_rows;
  col_end_ = width_ - image.ignore_last_cols;
  if (previous && previous->found && previous->rows == settings_.board.rows &&
      previous->cols == settings_.board.cols) {
    // Tracking reads only the board's rows: the luminance of those (and their margin) only. A fit
    // window that reaches the band's edge fails the tracking, which then searches the whole image.
    const auto [lo, hi] = tracking_rows(*previous);
    luminance_and_noise(image, lo, hi);
    const int usable_begin = row_begin_, usable_end = row_end_;
    row_begin_ = std::max(row_begin_, lo);
    row_end_ = std::min(row_end_, hi);
    const bool band = row_begin_ > usable_begin || row_end_ < usable_end;
    if (track(*previous, out, band)) return true;
    out.found = false;
    out.count = 0;
    row_begin_ = usable_begin;
    row_end_ = usable_end;
    if (!band) return full_search(out);
  }
  luminance_and_noise(image, 0, -1);
  return full_search(out);
}

void CornerDetector::luminance_and_noise(const RawImageView& image, int row_lo, int row_hi) {
  bayer_ = image.layout == PixelLayout::bayer_grbg;
  const int hi = row_hi < 0 ? height_ : row_hi;
  // The white balance is the sensor's and the light's, not the frame's: tracking keeps the one its
  // previous full search measured (two regressions over the mosaic cost more than the tracked fits).
  const bool keep = bayer_ && (row_lo > 0 || row_hi >= 0) && balance_.valid;
  if (!keep) balance_ = bayer_ ? estimate_cfa_balance(image, row_lo, hi) : CfaBalance{};
  // The defect test of textured frames: the same-site rule alone took the centres of a far board's
  // 4 px squares for hot pixels and flattened them (bench_conditions' 4 px Bayer row: no grid in
  // any eye; 9 of 12 pairs found with this rule, every other row the same within 0.0002 px RMS).
  raw_to_luminance(image, luma_.data(), scratch_.data(), kDefectThresholdDn, row_lo, row_hi, &balance_,
                   /*textured=*/true);
  // The noise of the (balanced) mosaic, then of the luminance: the 3 x 3 binomial's weights
  // squared sum to 36 / 256 (correlating neighbours, which residual_bound accounts for).
  mark_clipped(image, row_lo, hi);
  const float* mosaic = bayer_ ? scratch_.data() : luma_.data();
  const int r0 = std::max(row_lo, image.ignore_edge_rows),
            r1 = std::min(hi, height_ - image.ignore_edge_rows);
  // A clipped site of the balanced mosaic reads (1020 - offset) / gain: with a gain above 1 that is
  // below 1020, and a block of them (zero variance, heavy weight) would pull the noise line to the
  // quantisation floor (seen: sigma 0.1 DN where the truth is 2.5 on tilted and close boards).
  std::array<float, 4> clip;
  for (std::size_t k = 0; k < 4; ++k) {
    clip[k] = bayer_ && balance_.valid ? (kClipDn - balance_.offset[k]) / balance_.gain[k] : kClipDn;
  }
  const NoiseModel m = noise_estimator_.estimate(mosaic, width_, r0, r1, width_ - image.ignore_last_cols,
                                                 bayer_ ? 2 : 1, clip);
  const double f = bayer_ ? 36.0 / 256.0 : 1.0;
  noise_ = NoiseModel{m.a * f, m.b * f, m.levels};
}

void CornerDetector::mark_clipped(const RawImageView& image, int row_lo, int row_hi) {
  // A Bayer luminance pixel is the 3 x 3 binomial of its mosaic neighbourhood: one clipped site in it
  // (a balanced clipped site reads (1020 - offset) / gain, under the clip for a gain above 1) makes
  // a value that looks linear and is not. Mono pixels are judged by their own value (>= 1020).
  any_clipped_ = false;
  if (!bayer_) return;
  constexpr auto kClipRaw = static_cast<std::uint16_t>(kClipDn);
  const int w = width_, h = height_;
  // Reference rows are no light (the luminance replaces them by same-site neighbours).
  const int r0 = std::max(row_lo - 1, image.ignore_edge_rows);
  const int r1 = std::min(row_hi + 1, h - image.ignore_edge_rows);
  const int c_end = w - image.ignore_last_cols;
  for (int r = r0; r < r1 && !any_clipped_; ++r) {
    const std::uint16_t* p = image.data + static_cast<std::ptrdiff_t>(r) * image.stride;
    any_clipped_ = *std::max_element(p, p + c_end) >= kClipRaw;
  }
  if (!any_clipped_) return;
  // The 3 x 3 neighbourhood of every clipped site, within the rows read.
  std::fill(clipped_.begin() + static_cast<std::ptrdiff_t>(r0) * w,
            clipped_.begin() + static_cast<std::ptrdiff_t>(r1) * w, 0);
  for (int r = r0; r < r1; ++r) {
    const std::uint16_t* p = image.data + static_cast<std::ptrdiff_t>(r) * image.stride;
    for (int c = 0; c < c_end; ++c) {
      if (p[c] < kClipRaw) continue;
      for (int rr = std::max(r - 1, r0); rr <= std::min(r + 1, r1 - 1); ++rr)
        for (int cc = std::max(c - 1, 0); cc <= std::min(c + 1, w - 1); ++cc)
          clipped_[static_cast<std::size_t>(rr * w + cc)] = 1;
    }
  }
}

LumaView CornerDetector::luma_view() const {
  return LumaView{luma_.data(),
                  width_,
                  height_,
                  row_begin_,
                  row_end_,
                  col_end_,
                  any_clipped_ ? clipped_.data() : nullptr};
}

std::pair<int, int> CornerDetector::tracking_rows(const CornerResult& previous) const {
  double lo = height_, hi = 0, spacing = 0;
  for (int r = 0; r < previous.rows; ++r) {
    for (int c = 0; c < previous.cols; ++c) {
      const Eigen::Vector2d& p = previous.at(r, c).px;
      lo = std::min(lo, p.y());
      hi = std::max(hi, p.y());
      if (c + 1 < previous.cols) spacing = std::max(spacing, (previous.at(r, c + 1).px - p).norm());
      if (r + 1 < previous.rows) spacing = std::max(spacing, (previous.at(r + 1, c).px - p).norm());
    }
  }
  // What a corner's work reaches: its fit window (taper included), the polarity samples (up to 0.35
  // of the spacing), the allowed motion, and two rows of rounding.
  const double reach =
      std::max<double>(FastFitScratch::kMaxHalf, 0.35 * spacing + 2.0) + settings_.max_track_motion_px + 2.0;
  return {static_cast<int>(std::floor(lo - reach)), static_cast<int>(std::ceil(hi + reach)) + 1};
}

bool CornerDetector::track(const CornerResult& previous, CornerResult& out, bool band) {
  out.count = previous.count;
  out.corners = previous.corners;
  if (!refine_all(out, true)) return false;
  for (int i = 0; i < out.count && band; ++i) {
    if (out.corners[static_cast<std::size_t>(i)].flags & kCornerNearEdge) {
      failure_ = CornerFailure::track_moved;  // its window met the edge of the rows computed
      return false;
    }
  }
  for (int i = 0; i < out.count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    // A corner that moved by a sizeable part of the spacing may have locked onto its neighbour,
    // which would shift every id: refuse and search afresh.
    if ((out.corners[k].px - previous.corners[k].px).norm() > settings_.max_track_motion_px) {
      failure_ = CornerFailure::track_moved;
      return false;
    }
  }
  if (!validate(out)) return false;
  out.found = true;
  out.tracked = true;
  return true;
}

bool CornerDetector::full_search(CornerResult& out) {
  const LumaView v = luma_view();
  bool found = coarse_finder_.find(v, settings_.board.rows, settings_.board.cols, coarse_.data(), &noise_);
  bool from_opencv = false;
  if (!found && settings_.opencv_fallback) {
    found = from_opencv = coarse_grid_opencv(v, settings_.board.rows, settings_.board.cols, gray8_, coarse_);
  }
  if (!found) {
    failure_ = CornerFailure::no_grid;
    return false;
  }
  // A grid the fit or the validation refuses may be a texture's lattice found before the board's:
  // the lattice search goes on. The first refusal is what last_failure() reports when none passes.
  CornerFailure first_failure = CornerFailure::none;
  CornerRejection first_rejection;
  auto from_coarse = [&] {
    out.count = settings_.board.rows * settings_.board.cols;
    for (int i = 0; i < out.count; ++i) {
      Corner& c = out.corners[static_cast<std::size_t>(i)];
      c = Corner{};
      c.px = coarse_[static_cast<std::size_t>(i)].cast<double>();
    }
    canonical_order(out);
  };
  while (found) {
    from_coarse();
    if (refine_all(out, false) && validate(out)) {
      out.found = true;
      // A board of squares only a few pixels across (fitted as the checkerboard's fundamental) may
      // be a picture of a board beside the real one (OpenCV's left04 shows one on a monitor, squares
      // of ~4 px, found before the held board once such boards could be fitted): the search goes on,
      // and a further board whose corners are better measured (mean standard error) is the one
      // returned. Boards of ordinary squares return at once, as before.
      if (!harmonic_used_ || from_opencv) return true;
      auto mean_se = [](const CornerResult& r) {
        double sum = 0;
        for (int i = 0; i < r.count; ++i) sum += r.corners[static_cast<std::size_t>(i)].position_se_px;
        return sum / std::max(r.count, 1);
      };
      const CornerResult small = out;
      while (coarse_finder_.find_next(coarse_.data())) {
        from_coarse();
        if (refine_all(out, false) && validate(out) && mean_se(out) < mean_se(small)) {
          out.found = true;
          failure_ = CornerFailure::none;
          return true;
        }
      }
      out = small;
      failure_ = CornerFailure::none;
      return true;
    }
    out.count = 0;
    if (first_failure == CornerFailure::none) {
      first_failure = failure_;
      first_rejection = rejection_;
    }
    found = !from_opencv && coarse_finder_.find_next(coarse_.data());
  }
  failure_ = first_failure;
  rejection_ = first_rejection;
  return false;
}

bool CornerDetector::validate(const CornerResult& out) {
  // Every corner a saddle of the right polarity: a checkerboard alternates along rows and columns.
  const LumaView v = luma_view();
  const int p0 = corner_polarity(v, out, 0, 0);
  failure_ = CornerFailure::polarity;
  if (p0 == 0) return false;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      const int expect = ((r + c) % 2 == 0) ? p0 : -p0;
      if (corner_polarity(v, out, r, c) != expect) return false;
    }
  }
  // The grid must be the image of a plane: a homography in undistorted coordinates.
  double rms = 0, worst = 0;
  failure_ = CornerFailure::not_planar;
  if (!grid_plane_residual(out, camera_, rms, worst)) return false;
  if (rms > settings_.max_homography_rms_px || worst > settings_.max_homography_worst_px) return false;
  failure_ = CornerFailure::none;
  return true;
}

}  // namespace naneye::recon
