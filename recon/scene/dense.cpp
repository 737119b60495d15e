// The dense scene path (dense.hpp): exact rectification -> rectified matcher -> the left raw grid.
#include "naneye/recon/scene/dense.hpp"

#include <algorithm>
#include <cmath>

#include "dense_rectify.hpp"
#include "naneye/recon/geometry/calibration_sigma_table.hpp"
#include "select.hpp"

namespace naneye::recon::scene {
namespace {

// The raw pixels that carry image data (RawImageView's padding column and edge rows excluded).
cv::Mat active_mask(const CameraModel& cam) {
  const RawImageView layout;
  cv::Mat m = cv::Mat::zeros(cam.height(), cam.width(), CV_8UC1);
  m(cv::Rect(0, layout.ignore_edge_rows, cam.width() - layout.ignore_last_cols,
             cam.height() - 2 * layout.ignore_edge_rows))
      .setTo(1);
  return m;
}

MatcherSettings band(const StereoRig& rig, const DenseSettings& s) {
  // Disparity of depth Z on the rectified pair: f B / Z (f the left fx, dense_rectify.hpp).
  const double fb = rig.left.fx() * rig.right_center().norm();
  MatcherSettings m = s.matcher;
  m.min_disparity = std::max(0, static_cast<int>(std::floor(fb / s.z_max_mm)));
  const int top = static_cast<int>(std::ceil(fb / s.z_min_mm));
  m.num_disparities = (top - m.min_disparity + 1 + 15) / 16 * 16;  // SGBM wants a multiple of 16
  return m;
}

}  // namespace

struct DenseReconstructor::Impl {
  Impl(const StereoRig& r, const DenseSettings& st)
      : rig(r),
        s(st),
        rect(build_rectified_rig(r, active_mask(r.left), active_mask(r.right),
                                 band(r, st).min_disparity + band(r, st).num_disparities)),
        matcher(rect.width, rect.height, band(r, st)),
        calib(CalibrationSigmaTable::of(r, {.z_min_mm = st.z_min_mm, .z_max_mm = st.z_max_mm})) {
    left.create(rect.height, rect.width, CV_32FC1);
    right.create(rect.height, rect.width, CV_32FC1);
    const int w = rig.left.width(), h = rig.left.height();
    visible.assign(static_cast<std::size_t>(w) * h, 0);
    const cv::Mat active = active_mask(rig.left);
    const MatcherSettings& m = matcher.settings();
    // Both eyes can see the pixel when its rectified row meets the right's valid domain somewhere
    // in the disparity band (at the depth the scene has, which no geometry alone knows).
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) {
        const float ux = rect.raw_to_rect_x.at<float>(r, c), uy = rect.raw_to_rect_y.at<float>(r, c);
        if (!active.at<std::uint8_t>(r, c) || !std::isfinite(ux)) continue;
        const int x = static_cast<int>(std::lround(ux)), y = static_cast<int>(std::lround(uy));
        if (y < 0 || y >= rect.height || x < 0 || x >= rect.width || !rect.valid[0].at<std::uint8_t>(y, x))
          continue;
        bool seen = false;
        for (int d = m.min_disparity; d < m.min_disparity + m.num_disparities && !seen; ++d)
          seen = x - d >= 0 && rect.valid[1].at<std::uint8_t>(y, x - d);
        visible[static_cast<std::size_t>(r) * w + c] = seen ? 1 : 0;
        visible_count += seen;
      }
    depths.reserve(visible.size());
  }

  StereoRig rig;
  DenseSettings s;
  RectifiedRig rect;
  RectifiedMatcher matcher;
  cv::Mat left, right;
  std::vector<std::uint8_t> visible;
  int visible_count = 0;
  std::optional<CalibrationSigmaTable> calib;  // empty: the calibration has no covariance
  std::vector<float> depths;                   // scratch of the medians
  SelectHistogram hist;

  // DenseSettings::band_from_sparse: the band the seed's points need, inside the whole one.
  void set_band(const SparseResult* seed) {
    const DisparityBand whole{matcher.settings().min_disparity, matcher.settings().num_disparities};
    DisparityBand b = whole;
    if (s.band_from_sparse && seed && seed->valid_count >= s.min_band_points) {
      double dlo = std::numeric_limits<double>::infinity(), dhi = -dlo;
      for (const ScenePoint& p : seed->points) {
        if (!p.valid()) continue;
        const double d = rect.disparity_for(rect.R_left_rect.row(2).dot(p.X));
        dlo = std::min(dlo, d);
        dhi = std::max(dhi, d);
      }
      b = band_around(dlo, dhi, s.band_margin_px, whole);
    }
    matcher.set_band(b.min_disparity, b.num_disparities);
  }
};

DenseReconstructor::DenseReconstructor(const StereoRig& rig, const DenseSettings& s)
    : impl_(std::make_unique<Impl>(rig, s)) {}
DenseReconstructor::~DenseReconstructor() = default;
DenseReconstructor::DenseReconstructor(DenseReconstructor&&) noexcept = default;
DenseReconstructor& DenseReconstructor::operator=(DenseReconstructor&&) noexcept = default;
const StereoRig& DenseReconstructor::rig() const {
  return impl_->rig;
}
const DenseSettings& DenseReconstructor::settings() const {
  return impl_->s;
}
const RectifiedMatcher& DenseReconstructor::matcher() const {
  return impl_->matcher;
}
const MatchCounts& DenseReconstructor::match_counts() const {
  return impl_->matcher.counts();
}

void DenseReconstructor::reconstruct(const StereoLuma& luma, DepthMap& out, const SparseResult* seed) {
  Impl& m = *impl_;
  const RectifiedRig& rr = m.rect;
  m.set_band(seed);
  rr.resample(0, luma.left.data(), luma.width, m.left);
  rr.resample(1, luma.right.data(), luma.width, m.right);
  m.matcher.match(m.left, m.right, rr.valid[0], rr.valid[1]);
  const cv::Mat& D = m.matcher.disparity();
  const cv::Mat& S = m.matcher.sigma();

  const int w = luma.width, h = luma.height;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  out.width = w;
  out.height = h;
  out.z_mm.resize(n);
  out.sigma_mm.resize(n);
  out.calib_sigma_mm.resize(n);
  out.valid_count = 0;
  out.visible_count = m.visible_count;
  m.depths.clear();
  const Eigen::Matrix3d back = rr.R_left_rect.transpose();
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * w + c;
      out.z_mm[i] = DepthMap::kNone;
      out.sigma_mm[i] = DepthMap::kNone;
      out.calib_sigma_mm[i] = DepthMap::kNone;
      if (!m.visible[i]) continue;
      const float ux = rr.raw_to_rect_x.at<float>(r, c), uy = rr.raw_to_rect_y.at<float>(r, c);
      const int x0 = static_cast<int>(std::floor(ux)), y0 = static_cast<int>(std::floor(uy));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= rr.width || y0 + 1 >= rr.height) continue;
      const float d00 = D.at<float>(y0, x0), d01 = D.at<float>(y0, x0 + 1);
      const float d10 = D.at<float>(y0 + 1, x0), d11 = D.at<float>(y0 + 1, x0 + 1);
      // NaN fails both comparisons: any neighbour without a match leaves the pixel without depth.
      const float lo = std::min({d00, d01, d10, d11}), hi = std::max({d00, d01, d10, d11});
      if (!std::isfinite(d00 + d01 + d10 + d11) || !(hi - lo <= m.s.max_neighbour_spread_px)) continue;
      const float tx = ux - static_cast<float>(x0), ty = uy - static_cast<float>(y0);
      const double d = (1 - ty) * ((1 - tx) * d00 + tx * d01) + ty * ((1 - tx) * d10 + tx * d11);
      const double sd = (1 - ty) * ((1 - tx) * S.at<float>(y0, x0) + tx * S.at<float>(y0, x0 + 1)) +
                        ty * ((1 - tx) * S.at<float>(y0 + 1, x0) + tx * S.at<float>(y0 + 1, x0 + 1));
      if (!(d > 0)) continue;
      // The rectified point at disparity d: X_rect = B / d (u - cx, v - cy, f); Z in the left frame.
      const Eigen::Vector3d q(ux - rr.cx, uy - rr.cy, rr.f);
      const double z = rr.baseline_mm / d * back.row(2).dot(q);
      if (!(z > 0)) continue;
      out.z_mm[i] = static_cast<float>(z);
      out.sigma_mm[i] = static_cast<float>(z * sd / d);  // Z is proportional to 1 / d
      if (m.calib) out.calib_sigma_mm[i] = m.calib->depth_sigma_mm(c, r, rr.baseline_mm / d * (back * q));
      ++out.valid_count;
      m.depths.push_back(static_cast<float>(z));
    }
  out.valid_share = out.visible_count > 0 ? static_cast<double>(out.valid_count) / out.visible_count : 0.0;
  out.median_mm = std::numeric_limits<double>::quiet_NaN();
  if (!m.depths.empty()) {
    out.median_mm = kth_smallest(m.depths.data(), m.depths.size(), m.depths.size() / 2, m.hist);
  }
  out.calib_sigma_median_mm = std::numeric_limits<double>::quiet_NaN();
  if (m.calib && !m.depths.empty()) {
    m.depths.clear();
    for (float c : out.calib_sigma_mm)
      if (std::isfinite(c)) m.depths.push_back(c);
    out.calib_sigma_median_mm = kth_smallest(m.depths.data(), m.depths.size(), m.depths.size() / 2, m.hist);
  }
}

}  // namespace naneye::recon::scene
