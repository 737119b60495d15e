// The lattice of the full-search coarse grid (corners/coarse_grid.hpp): saddle candidates are taken to
// undistorted coordinates, where the board's corners are the image of a plane under a homography,
// so the step between neighbours changes slowly and a neighbour is predicted by linear
// extrapolation. The grid grows from a seed square of four saddles until no prediction finds a
// saddle; only a complete component of exactly rows x cols corners is returned.
#include <algorithm>
#include <array>
#include <cmath>

#include "naneye/recon/corners/coarse_grid.hpp"

namespace naneye::recon {

namespace {
// Cells a component may hold beyond the pattern's (false links, left out).
constexpr int kMaxStrayCells = 2;
constexpr int kMaxCells = 2 * kMaxCorners + 64;
constexpr std::array<std::array<int, 2>, 4> kDirs = {{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};

// Grid neighbours alternate polarity: their second harmonics point in opposite directions.
bool same_polarity(const SaddleCandidate& a, const SaddleCandidate& b) {
  return (a.phase * std::conj(b.phase)).real() > 0;
}
}  // namespace

int CoarseGridFinder::nearest(const Eigen::Vector2f& at, float radius, int polarity_of, bool same) const {
  const SaddleCandidate& ref = cand_[static_cast<std::size_t>(polarity_of)];
  int best = -1;
  float best_d2 = radius * radius;
  for (int i = 0; i < count_; ++i) {
    const SaddleCandidate& c = cand_[static_cast<std::size_t>(i)];
    if (!c.usable || i == polarity_of || same_polarity(c, ref) != same) continue;
    const float d2 = (c.und - at).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = i;
    }
  }
  return best;
}

bool CoarseGridFinder::seed_square(int seed, int& a, int& b, int& d) const {
  // The four nearest saddles of the other polarity; on a lattice seen at up to ~50 degrees of tilt
  // the grid neighbours are nearer than the diagonals.
  const SaddleCandidate& s = cand_[static_cast<std::size_t>(seed)];
  std::array<int, 4> near{-1, -1, -1, -1};
  std::array<float, 4> dist{1e30f, 1e30f, 1e30f, 1e30f};
  for (int i = 0; i < count_; ++i) {
    const SaddleCandidate& c = cand_[static_cast<std::size_t>(i)];
    if (!c.usable || i == seed || same_polarity(c, s)) continue;
    const float d2 = (c.und - s.und).squaredNorm();
    for (std::size_t k = 0; k < 4; ++k) {
      if (d2 < dist[k]) {
        for (std::size_t m = 3; m > k; --m) {
          dist[m] = dist[m - 1];
          near[m] = near[m - 1];
        }
        dist[k] = d2;
        near[k] = i;
        break;
      }
    }
  }
  // The first pair of neighbours (nearest first) spanning a plausible cell whose fourth corner is a
  // saddle of the seed's polarity.
  for (std::size_t i = 0; i < 4 && near[i] >= 0; ++i) {
    for (std::size_t j = i + 1; j < 4 && near[j] >= 0; ++j) {
      const Eigen::Vector2f e1 = cand_[static_cast<std::size_t>(near[i])].und - s.und;
      const Eigen::Vector2f e2 = cand_[static_cast<std::size_t>(near[j])].und - s.und;
      const float n1 = e1.norm(), n2 = e2.norm();
      if (n2 > 2.0f * n1 || n1 > 2.0f * n2) continue;
      if (std::abs(e1.dot(e2)) > 0.77f * n1 * n2) continue;  // axes 40..140 degrees apart
      const int diag = nearest(s.und + e1 + e2, s_.lattice_tolerance * std::min(n1, n2), seed, true);
      if (diag < 0) continue;
      a = near[i];
      b = near[j];
      d = diag;
      return true;
    }
  }
  return false;
}

int CoarseGridFinder::grow(int seed, int rows, int cols, Eigen::Vector2f* out) {
  int a = -1, b = -1, d = -1;
  if (!seed_square(seed, a, b, d)) return 0;
  const int side = 2 * std::max(rows, cols) + 3, o = side / 2;
  // Room for a ring of cells around the pattern: the outer corners of the border squares (L- and
  // T-junctions where the squares meet the board's margin or a background of similar grey), which
  // a cluttered photograph lets pass the ring test. The placement below tells them apart.
  const int limit = std::min((rows + 2) * (cols + 2), kMaxCells);
  std::fill(grid_.begin(), grid_.begin() + side * side, -1);
  std::array<std::array<int, 2>, kMaxCells> cells{};
  int n = 0;
  ++stamp_;
  auto put = [&](int i, int j, int c) {
    grid_[static_cast<std::size_t>(j * side + i)] = c;
    cell_of_[static_cast<std::size_t>(c)] = stamp_;
    cells[static_cast<std::size_t>(n++)] = {i, j};
  };
  auto at = [&](int i, int j) {
    return (i < 0 || j < 0 || i >= side || j >= side) ? -1 : grid_[static_cast<std::size_t>(j * side + i)];
  };
  put(o, o, seed);
  put(o + 1, o, a);
  put(o, o + 1, b);
  put(o + 1, o + 1, d);
  bool changed = true;
  while (changed) {
    changed = false;
    for (int k = 0; k < n; ++k) {
      const int i = cells[static_cast<std::size_t>(k)][0], j = cells[static_cast<std::size_t>(k)][1];
      const int here = at(i, j);
      const Eigen::Vector2f p = cand_[static_cast<std::size_t>(here)].und;
      for (const auto& dir : kDirs) {
        const int ti = i + dir[0], tj = j + dir[1];
        if (ti < 0 || tj < 0 || ti >= side || tj >= side) return -1;  // longer than any pattern
        if (at(ti, tj) >= 0) continue;
        // Prediction: extrapolate from the cell behind, else copy the step of a side neighbour.
        Eigen::Vector2f step;
        const int back = at(i - dir[0], j - dir[1]);
        if (back >= 0) {
          step = p - cand_[static_cast<std::size_t>(back)].und;
        } else {
          int s0 = -1, s1 = -1;
          for (int side_sign = -1; side_sign <= 1 && s1 < 0; side_sign += 2) {
            const int si = i + side_sign * dir[1], sj = j + side_sign * dir[0];
            s0 = at(si, sj);
            s1 = s0 >= 0 ? at(si + dir[0], sj + dir[1]) : -1;
          }
          if (s1 < 0) continue;
          step = cand_[static_cast<std::size_t>(s1)].und - cand_[static_cast<std::size_t>(s0)].und;
        }
        const int c = nearest(p + step, s_.lattice_tolerance * step.norm(), here, false);
        if (c < 0 || cell_of_[static_cast<std::size_t>(c)] == stamp_) continue;
        if (n == limit) return -1;  // more saddles than the pattern has: a larger board
        put(ti, tj, c);
        changed = true;
      }
    }
  }
  int i0 = side, i1 = -1, j0 = side, j1 = -1;
  for (int k = 0; k < n; ++k) {
    i0 = std::min(i0, cells[static_cast<std::size_t>(k)][0]);
    i1 = std::max(i1, cells[static_cast<std::size_t>(k)][0]);
    j0 = std::min(j0, cells[static_cast<std::size_t>(k)][1]);
    j1 = std::max(j1, cells[static_cast<std::size_t>(k)][1]);
  }
  // The pattern must sit in the component at exactly one place (either way round): two places means
  // a larger board (nothing is certain), none means part of a board (cut by the edge, or a saddle
  // missed). A few cells beyond it are false links (the border squares' outer corners under strong
  // distortion can pass the ring test) and are left out. A placement is certain when every cell of the
  // component outside it is a false link (at most kMaxStrayCells of them) or not an X-junction: its ring
  // symmetry (second over first harmonic) below max_outer_symmetry, where every inner corner of the placement
  // is above it.
  int placements = 0, uncertain = 0, pi = 0, pj = 0;
  bool p_i_is_col = true;
  for (int orient = 0; orient < (rows == cols ? 1 : 2); ++orient) {
    const int w = orient == 0 ? cols : rows, h = orient == 0 ? rows : cols;
    for (int j = j0; j + h - 1 <= j1; ++j) {
      for (int i = i0; i + w - 1 <= i1; ++i) {
        bool complete = true;
        float inner = 1e30f;
        for (int jj = j; jj < j + h && complete; ++jj) {
          for (int ii = i; ii < i + w; ++ii) {
            const int c = at(ii, jj);
            if (c < 0) {
              complete = false;
              break;
            }
            inner = std::min(inner, cand_[static_cast<std::size_t>(c)].symmetry);
          }
        }
        if (!complete) continue;
        // The component's cells next to the placement (a row or column beyond it) that are
        // X-junctions: a larger board's next row. Its L- and T-junctions (the border squares'
        // outer corners) and links further out (clutter) do not make another placement.
        int adjacent_x = 0, outside = 0;
        for (int k = 0; k < n; ++k) {
          const int ci = cells[static_cast<std::size_t>(k)][0], cj = cells[static_cast<std::size_t>(k)][1];
          if (ci >= i && ci < i + w && cj >= j && cj < j + h) continue;
          ++outside;
          const bool next = ci >= i - 1 && ci <= i + w && cj >= j - 1 && cj <= j + h;
          adjacent_x += next && cand_[static_cast<std::size_t>(at(ci, cj))].symmetry >= s_.max_outer_symmetry;
        }
        // Up to kMaxStrayCells cells beyond the pattern are false links, whatever they look like.
        // Beyond that, the placement must be all X-junctions (a placement over a row of L-corners
        // is not the pattern) with at most kMaxStrayCells X-junctions beside it (more: a larger
        // board's next row, nothing is certain).
        if (outside > kMaxStrayCells) {
          if (inner < s_.max_outer_symmetry) continue;
          if (adjacent_x > kMaxStrayCells) {
            ++uncertain;
            continue;
          }
        }
        ++placements;
        pi = i;
        pj = j;
        p_i_is_col = orient == 0;
      }
    }
  }
  if (placements > 1 || uncertain > 0) return -1;
  if (placements == 0) return 0;
  for (int j = 0; j < (p_i_is_col ? rows : cols); ++j) {
    for (int i = 0; i < (p_i_is_col ? cols : rows); ++i) {
      const int idx = p_i_is_col ? j * cols + i : i * cols + j;
      out[idx] = cand_[static_cast<std::size_t>(at(pi + i, pj + j))].px;
    }
  }
  return 1;
}

bool CoarseGridFinder::find(const LumaView& img, int rows, int cols, Eigen::Vector2f* out,
                            const NoiseModel* noise) {
  count_ = 0;
  noise_ = noise;
  if (img.width != width_ || img.height != height_ || rows < 2 || cols < 2 || rows * cols > kMaxCorners) {
    return false;
  }
  saddle_map(img);
  collect_candidates(img);
  int usable = 0;
  for (int i = 0; i < count_; ++i) {
    SaddleCandidate& c = cand_[static_cast<std::size_t>(i)];
    c.usable = undistort_px(c.px, c.und);
    if (c.usable) {
      order_[static_cast<std::size_t>(usable++)] = i;
    }
    cell_of_[static_cast<std::size_t>(i)] = -1;
  }
  if (usable < rows * cols) return false;
  std::sort(order_.begin(), order_.begin() + usable, [&](int x, int y) {
    return cand_[static_cast<std::size_t>(x)].response > cand_[static_cast<std::size_t>(y)].response;
  });
  // Seeds from the strongest saddle down; a seed already in an earlier (incomplete) component would
  // only grow the same component again.
  int tried = 0;
  stamp_ = 0;
  for (int k = 0; k < usable && tried < s_.max_seeds; ++k) {
    const int seed = order_[static_cast<std::size_t>(k)];
    if (cell_of_[static_cast<std::size_t>(seed)] >= 0) continue;
    ++tried;
    const int r = grow(seed, rows, cols, out);
    if (r != 0) return r > 0;
  }
  return false;
}

}  // namespace naneye::recon
