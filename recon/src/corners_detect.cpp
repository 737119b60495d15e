#include <algorithm>
#include <cmath>

#include "naneye/recon/corners.hpp"
#include "naneye/recon/corners_grid.hpp"
#include "naneye/recon/corners_refine.hpp"

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

CornerDetector::CornerDetector(const CameraModel& camera, const CornerSettings& settings)
    : camera_(camera), settings_(settings), width_(camera.width()), height_(camera.height()) {
  luma_.resize(static_cast<std::size_t>(width_) * height_);
  gray8_.resize(luma_.size());
  coarse_.reserve(kMaxCorners);
}

bool CornerDetector::detect(const RawImageView& image, const CornerResult* previous, CornerResult& out) {
  out.found = false;
  out.tracked = false;
  out.count = 0;
  out.rows = settings_.rows;
  out.cols = settings_.cols;
  if (image.width != width_ || image.height != height_ || !image.data ||
      settings_.rows * settings_.cols > kMaxCorners) {
    return false;
  }
  raw_to_luminance(image, luma_.data());
  row_begin_ = image.ignore_edge_rows;
  row_end_ = height_ - image.ignore_edge_rows;
  col_end_ = width_ - image.ignore_last_cols;
  if (previous && previous->found && previous->rows == settings_.rows && previous->cols == settings_.cols) {
    if (track(*previous, out)) return true;
    out.found = false;
    out.count = 0;
  }
  return full_search(out);
}

bool CornerDetector::track(const CornerResult& previous, CornerResult& out) {
  out.count = previous.count;
  out.corners = previous.corners;
  if (!refine_all(out, true)) return false;
  for (int i = 0; i < out.count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    // A corner that moved by a sizeable part of the spacing may have locked onto its neighbour,
    // which would shift every id: refuse and search afresh.
    if ((out.corners[k].px - previous.corners[k].px).norm() > settings_.max_track_motion_px) return false;
  }
  if (!validate(out)) return false;
  out.found = true;
  out.tracked = true;
  return true;
}

bool CornerDetector::full_search(CornerResult& out) {
  const LumaView v{luma_.data(), width_, height_, row_begin_, row_end_, col_end_};
  if (!coarse_grid_opencv(v, settings_.rows, settings_.cols, gray8_, coarse_)) return false;
  out.count = settings_.rows * settings_.cols;
  for (int i = 0; i < out.count; ++i) {
    Corner& c = out.corners[static_cast<std::size_t>(i)];
    c = Corner{};
    c.px = coarse_[static_cast<std::size_t>(i)].cast<double>();
  }
  canonical_order(out);
  if (!refine_all(out, false) || !validate(out)) {
    out.count = 0;
    return false;
  }
  out.found = true;
  return true;
}

bool CornerDetector::refine_all(CornerResult& out, bool from_previous) {
  const LumaView v{luma_.data(), width_, height_, row_begin_, row_end_, col_end_};
  // Grid directions and spacing come from the coarse (or previous) positions, before any is moved.
  std::array<Eigen::Vector2d, kMaxCorners> start;
  for (int i = 0; i < out.count; ++i)
    start[static_cast<std::size_t>(i)] = out.corners[static_cast<std::size_t>(i)].px;
  auto pos = [&](int r, int c) { return start[static_cast<std::size_t>(r * out.cols + c)]; };
  constexpr double kHalfPi = 1.57079632679489661923;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      Corner& k = out.corners[static_cast<std::size_t>(r * out.cols + c)];
      const int c0 = std::max(c - 1, 0), c1 = std::min(c + 1, out.cols - 1);
      const int r0 = std::max(r - 1, 0), r1 = std::min(r + 1, out.rows - 1);
      const Eigen::Vector2d dc = (pos(r, c1) - pos(r, c0)) / (c1 - c0);
      const Eigen::Vector2d dr = (pos(r1, c) - pos(r0, c)) / (r1 - r0);
      const double spacing = std::min(dc.norm(), dr.norm());
      // The window must not reach the neighbouring corners' edges (blur included).
      int half =
          std::clamp(static_cast<int>(0.45 * spacing), settings_.min_half_window, settings_.max_half_window);
      SaddleInit init;
      init.px = pos(r, c);
      if (from_previous && k.sigma_px > 0) {
        init.theta1 = k.theta_row;
        init.theta2 = k.theta_col;
        init.sigma = k.sigma_px;
      } else {
        init.theta1 = std::atan2(dc.y(), dc.x()) + kHalfPi;  // normal of the edge along the row
        init.theta2 = std::atan2(dr.y(), dr.x()) + kHalfPi;  // normal of the edge along the column
        init.sigma = 0.8;
      }
      SaddleFit fit;
      std::uint8_t flags = 0;
      bool ok = fit_saddle(v, camera_, init, half, 20, fit);
      while (!ok && half > settings_.min_half_window) {
        const int cx = static_cast<int>(std::lround(init.px.x())),
                  cy = static_cast<int>(std::lround(init.px.y()));
        const bool at_edge =
            cx - half < 0 || cx + half >= col_end_ || cy - half < row_begin_ || cy + half >= row_end_;
        if (!at_edge) break;
        --half;
        flags |= kCornerNearEdge;
        ok = fit_saddle(v, camera_, init, half, 20, fit);
      }
      if (!ok) return false;
      if (fit.contrast < settings_.min_contrast_dn ||
          fit.rms > settings_.max_relative_residual * fit.contrast || fit.sigma < settings_.min_sigma_px ||
          fit.sigma > settings_.max_sigma_px) {
        return false;
      }
      if (fit.rms > 0.5 * settings_.max_relative_residual * fit.contrast) flags |= kCornerFitPoor;
      if (!fit.undistorted || !camera_.in_domain(fit.px)) flags |= kCornerBeyondFold;
      k.px = fit.px;
      k.row = r;
      k.col = c;
      k.flags = flags;
      k.sigma_px = fit.sigma;
      k.contrast = 2.0 * fit.contrast;
      k.residual = fit.rms;
      k.theta_row = fit.theta1;
      k.theta_col = fit.theta2;
    }
  }
  return true;
}

bool CornerDetector::validate(const CornerResult& out) const {
  // Every corner a saddle of the right polarity: a checkerboard alternates along rows and columns.
  const LumaView v{luma_.data(), width_, height_, row_begin_, row_end_, col_end_};
  const int p0 = corner_polarity(v, out, 0, 0);
  if (p0 == 0) return false;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      const int expect = ((r + c) % 2 == 0) ? p0 : -p0;
      if (corner_polarity(v, out, r, c) != expect) return false;
    }
  }
  // The grid must be the image of a plane: a homography in undistorted coordinates.
  double rms = 0, worst = 0;
  if (!grid_homography_residual(out, camera_, rms, worst)) return false;
  return rms <= settings_.max_homography_rms_px && worst <= settings_.max_homography_worst_px;
}

}  // namespace naneye::recon
