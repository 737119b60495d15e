#include "naneye/recon/corners/grid.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

namespace naneye::recon {

bool coarse_grid_opencv(const LumaView& img, int rows, int cols, std::vector<unsigned char>& gray8,
                        std::vector<Eigen::Vector2f>& coarse) {
  // Stretch the usable area's 1st..99th percentile to 0..255 (10-bit DN would be clipped or too
  // dark for OpenCV's 8-bit detectors; the dark background and hot pixels must not set the scale).
  std::array<int, 1024> hist{};
  int n = 0;
  for (int r = img.row_begin; r < img.row_end; ++r) {
    for (int c = 0; c < img.col_end; ++c) {
      ++hist[static_cast<std::size_t>(std::clamp(static_cast<int>(img.at(r, c)), 0, 1023))];
      ++n;
    }
  }
  int lo = 0, hi = 1023, acc = 0;
  for (int v = 0; v < 1024; ++v) {
    acc += hist[static_cast<std::size_t>(v)];
    if (acc <= n / 100) lo = v;
    if (acc < n - n / 100) hi = v + 1;
  }
  if (hi <= lo) return false;
  gray8.resize(static_cast<std::size_t>(img.width) * img.height);
  const float scale = 255.0f / static_cast<float>(hi - lo);
  for (int i = 0; i < img.width * img.height; ++i) {
    gray8[static_cast<std::size_t>(i)] =
        static_cast<unsigned char>(std::clamp((img.data[i] - static_cast<float>(lo)) * scale, 0.0f, 255.0f));
  }
  const cv::Mat gray(img.height, img.width, CV_8UC1, gray8.data());
  std::vector<cv::Point2f> pts;
  bool ok = cv::findChessboardCorners(gray, cv::Size(cols, rows), pts,
                                      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (!ok) ok = cv::findChessboardCornersSB(gray, cv::Size(cols, rows), pts, cv::CALIB_CB_NORMALIZE_IMAGE);
  if (!ok || static_cast<int>(pts.size()) != rows * cols) return false;
  coarse.resize(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) coarse[i] = {pts[i].x, pts[i].y};
  return true;
}

namespace {
float bilinear(const LumaView& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < img.row_begin || x0 + 1 >= img.col_end || y0 + 1 >= img.row_end) return -1.0f;
  const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
  const float a = img.at(y0, x0), b = img.at(y0, x0 + 1), c = img.at(y0 + 1, x0), d = img.at(y0 + 1, x0 + 1);
  return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}
}  // namespace

int corner_polarity(const LumaView& img, const CornerResult& r, int row, int col) {
  // Grid directions from the neighbours (one-sided at the grid's border).
  const Eigen::Vector2d p = r.at(row, col).px;
  const int c0 = std::max(col - 1, 0), c1 = std::min(col + 1, r.cols - 1);
  const int r0 = std::max(row - 1, 0), r1 = std::min(row + 1, r.rows - 1);
  const Eigen::Vector2d dc = (r.at(row, c1).px - r.at(row, c0).px) / (c1 - c0);
  const Eigen::Vector2d dr = (r.at(r1, col).px - r.at(r0, col).px) / (r1 - r0);
  return quadrant_polarity(img, p, dc, dr);
}

int quadrant_polarity(const LumaView& img, const Eigen::Vector2d& p, const Eigen::Vector2d& dc,
                      const Eigen::Vector2d& dr, bool square_centres) {
  // Quadrant centres at 0.35 of the spacing along each diagonal; for a corner near the image border
  // (every corner in view, but the outer squares cut by the edge) closer, down to 0.18, as long as the
  // samples stay >= 2.5 px from the corner (outside its blur, a few tenths of a pixel here).
  // Squares under ~5 px (a far board) put 0.35 of the diagonal closer than that: there the samples
  // go to the squares' centres (0.5), the points farthest from every edge the grid has (half a
  // square from each: 2 px for 4 px squares, 2 blurs of the real sensor's ~1 px).
  float va = -1, vb = -1, vc = -1, vd = -1;
  const bool small = square_centres && std::min((0.35 * (dc + dr)).norm(), (0.35 * (dc - dr)).norm()) < 2.5;
  for (const double f : {small ? 0.5 : 0.35, 0.25, 0.18}) {
    const Eigen::Vector2d s1 = f * (dc + dr), s2 = f * (dc - dr);
    // A square's centre is the best a small square has: there 2.0 px from the corner (squares of
    // ~2.8 px, under 3 blurs: no board the fits could measure) is the floor.
    if (std::min(s1.norm(), s2.norm()) < (f == 0.5 ? 2.0 : 2.5)) break;
    const Eigen::Vector2d a = p + s1, b = p - s1, c = p + s2, d = p - s2;
    va = bilinear(img, a.x(), a.y());
    vb = bilinear(img, b.x(), b.y());
    vc = bilinear(img, c.x(), c.y());
    vd = bilinear(img, d.x(), d.y());
    if (va >= 0 && vb >= 0 && vc >= 0 && vd >= 0) break;
  }
  if (va < 0 || vb < 0 || vc < 0 || vd < 0) return 0;
  const float diag1 = std::min(va, vb), diag2 = std::min(vc, vd);
  const float diag1_max = std::max(va, vb), diag2_max = std::max(vc, vd);
  // Both quadrants of one diagonal must be brighter than both of the other, by at least half the
  // difference of the diagonals' means: an X-junction's quadrants pair up (ratio ~1, less the
  // shading), while an L- or T-junction at the board's border has two quadrants on the margin at
  // one level (ratio ~0 whatever that grey is), which a fit with linear shading can pass.
  const float mean_gap = 0.5f * std::abs((va + vb) - (vc + vd));
  if (diag1 > diag2_max && diag1 - diag2_max >= 0.5f * mean_gap) return 1;
  if (diag2 > diag1_max && diag2 - diag1_max >= 0.5f * mean_gap) return -1;
  return 0;
}

bool grid_line_continues(const LumaView& img, const Eigen::Vector2d& p, const Eigen::Vector2d& u,
                         const Eigen::Vector2d& v) {
  // Samples a quarter step on either side of the line, at a quarter, half and three quarters of the
  // step along it: every sample a quarter step from each edge of its square, which must be >= 2.5 px
  // (quadrant_polarity's bound: outside the edges' blur). Smaller squares cannot be told apart here.
  if (0.25 * std::min(u.norm(), v.norm()) < 2.5) return true;
  for (const double t : {0.25, 0.5, 0.75}) {
    const Eigen::Vector2d o = p + t * u, i = p - t * u;
    const float o1 = bilinear(img, (o + 0.25 * v).x(), (o + 0.25 * v).y());
    const float o2 = bilinear(img, (o - 0.25 * v).x(), (o - 0.25 * v).y());
    const float i1 = bilinear(img, (i + 0.25 * v).x(), (i + 0.25 * v).y());
    const float i2 = bilinear(img, (i - 0.25 * v).x(), (i - 0.25 * v).y());
    // Beyond the image the line cannot be followed: what was seen up to there decides (nothing
    // seen: it may continue, and the placement stays uncertain).
    if (o1 < 0 || o2 < 0 || i1 < 0 || i2 < 0) return true;
    // Across the junction the squares swap colour: the outer line's contrast has the inner line's
    // opposite sign, and at least half its size at the same distance from the junction (the margin
    // the quadrant test allows an X-junction's pairs; shading over a step changes it by less).
    const float inner = i1 - i2, outer = o1 - o2;
    if (!(-outer * (inner > 0 ? 1.0f : -1.0f) >= 0.5f * std::abs(inner))) return false;
  }
  return true;
}

}  // namespace naneye::recon
