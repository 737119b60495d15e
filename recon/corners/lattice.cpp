// The lattice of the full-search coarse grid (corners/coarse_grid.hpp): saddle candidates are taken to
// undistorted coordinates, where the board's corners are the image of a plane under a homography,
// so the step between neighbours changes slowly and a neighbour is predicted by linear
// extrapolation. The grid grows from a seed square of four saddles until no prediction finds a
// saddle; only a complete component of exactly rows x cols corners is returned.
#include <algorithm>
#include <array>
#include <cmath>
#include <span>

#include "naneye/base/median.hpp"
#include "naneye/recon/corners/coarse_grid.hpp"
#include "naneye/recon/corners/grid.hpp"

namespace naneye::recon {

namespace {
// Cells a component may hold beyond the pattern's (false links, left out).
constexpr int kMaxStrayCells = 2;
// Interior cells the saddle map missed that the lattice fills by interpolation (a clipped X-junction,
// where the bright quadrants' blur joins across the corner and splits the dark ones, has no saddle
// at its centre; a defect pixel or the reset line on a corner can do the same). The evidence of a
// board is its saddles: a few predictions among 48 are confirmed or refused by the fit, the quadrant
// test and the plane test like any corner; a lattice made mostly of predictions is no board's.
constexpr int kMaxFilledHoles = 4;
// A filled hole's raw position, undistorted again, within this of where it was put (px): 5x the
// tabulated undistortion's own error (0.02 px); where the projection folds back it fails.
constexpr float kHoleRoundTripPx = 0.1f;
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
  // Filled holes are candidates of this growth only: a component that is no board drops them.
  const int own_count = count_;
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
  int holes = 0;
  // An empty cell between two cells of the component (along either axis), undistorted coordinates
  // interpolated: a homography's midpoint is off by the second order of the step's change, far less
  // than the lattice's own tolerance (0.3 of the step) from which the fits start anyway. The raw
  // position must undistort back to it within kHoleRoundTripPx (not beyond the fold).
  // The component's bounding box of cells, [i0, i1] x [j0, j1].
  auto bounds = [&](int& i0, int& i1, int& j0, int& j1) {
    i0 = side, i1 = -1, j0 = side, j1 = -1;
    for (int k = 0; k < n; ++k) {
      i0 = std::min(i0, cells[static_cast<std::size_t>(k)][0]);
      i1 = std::max(i1, cells[static_cast<std::size_t>(k)][0]);
      j0 = std::min(j0, cells[static_cast<std::size_t>(k)][1]);
      j1 = std::max(j1, cells[static_cast<std::size_t>(k)][1]);
    }
  };
  auto fill_hole = [&]() {
    int i0, i1, j0, j1;
    bounds(i0, i1, j0, j1);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        if (at(i, j) >= 0) continue;
        Eigen::Vector2f sum = Eigen::Vector2f::Zero();
        int pairs = 0, other = -1;
        for (const auto& [di, dj] : {std::array<int, 2>{1, 0}, std::array<int, 2>{0, 1}}) {
          const int u = at(i - di, j - dj), v = at(i + di, j + dj);
          if (u < 0 || v < 0) continue;
          sum += 0.5f * (cand_[static_cast<std::size_t>(u)].und + cand_[static_cast<std::size_t>(v)].und);
          ++pairs;
          other = u;
        }
        if (pairs == 0 || count_ >= kCandidateCapacity || n == limit) continue;
        const Eigen::Vector2f und = sum / static_cast<float>(pairs);
        const double f = cam_.fx();
        const Eigen::Vector2d px = cam_.project(Eigen::Vector3d(und.x() / f, und.y() / f, 1.0));
        Eigen::Vector2f back;
        if (!px.allFinite() || !undistort_px(px.cast<float>(), back) ||
            (back - und).norm() > kHoleRoundTripPx) {
          continue;
        }
        SaddleCandidate& c = cand_[static_cast<std::size_t>(count_)];
        c.px = px.cast<float>();
        c.und = und;
        c.phase = -cand_[static_cast<std::size_t>(other)].phase;  // grid neighbours alternate
        c.response = 0;
        c.usable = true;
        put(i, j, count_++);
        return true;
      }
    }
    return false;
  };
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
  // Holes only once the growth has stopped, and no growth from them: a filled cell must not extend
  // the component (a photograph's ring of border-square corners would grow into a larger board).
  while (holes < kMaxFilledHoles && fill_hole()) ++holes;
  int i0, i1, j0, j1;
  bounds(i0, i1, j0, j1);
  // The pattern must sit in the component at exactly one place (either way round): two places means
  // a larger board (nothing is certain), none means part of a board (cut by the edge, or a saddle
  // missed). A few cells beyond it are false links (the border squares' outer corners under strong
  // distortion can pass the ring test) and are left out. Beyond kMaxStrayCells, the component holds
  // the border squares' outer corners (L- and T-junctions against the margin) or clutter: a placement
  // then counts only when every corner in it is an X-junction by the quadrant test (the one the
  // validation applies after the fit: both quadrants of one diagonal brighter than both of the other,
  // alternating over the grid), and it is uncertain when more than kMaxStrayCells cells beside it are
  // X-junctions of the same alternation too (a larger board's next row).
  // A cell's grid steps in raw pixels from its neighbours in the component (one-sided at its edge).
  auto steps = [&](int i, int j, Eigen::Vector2d& dc, Eigen::Vector2d& dr) {
    auto px = [&](int ii, int jj) { return cand_[static_cast<std::size_t>(at(ii, jj))].px.cast<double>(); };
    auto axis = [&](int di, int dj, Eigen::Vector2d& d) {
      const bool fwd = at(i + di, j + dj) >= 0, back = at(i - di, j - dj) >= 0;
      if (fwd && back)
        d = 0.5 * (px(i + di, j + dj) - px(i - di, j - dj));
      else if (fwd)
        d = px(i + di, j + dj) - px(i, j);
      else if (back)
        d = px(i, j) - px(i - di, j - dj);
      return fwd || back;
    };
    return axis(1, 0, dc) && axis(0, 1, dr);
  };
  // Quadrant polarity of every cell (0: no X-junction, or no neighbour to measure its steps by),
  // times the lattice's alternation, so that all X-junctions of one board share one sign.
  // A far board's squares are sampled at their centres (quadrant_polarity), but only at cells whose
  // steps are the component's own (within the lattice tolerance of its median step): a false link
  // between a board's saddle and clutter has a short step too, and its square centres would sit on
  // no square (seen on OpenCV's left04, where such a cell let a wrong placement through).
  std::array<float, kMaxCells> step_len{};
  int with_steps = 0;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector2d dc, dr;
    if (steps(cells[static_cast<std::size_t>(k)][0], cells[static_cast<std::size_t>(k)][1], dc, dr)) {
      step_len[static_cast<std::size_t>(with_steps++)] = static_cast<float>(std::min(dc.norm(), dr.norm()));
    }
  }
  const double median_step =
      base::upper_median(std::span(step_len).first(static_cast<std::size_t>(with_steps)));
  std::array<int, kMaxCells> sign{};
  for (int k = 0; k < n; ++k) {
    const int ci = cells[static_cast<std::size_t>(k)][0], cj = cells[static_cast<std::size_t>(k)][1];
    Eigen::Vector2d dc, dr;
    const bool has_steps = steps(ci, cj, dc, dr);
    const bool own_steps =
        has_steps && std::min(dc.norm(), dr.norm()) >= (1.0 - s_.lattice_tolerance) * median_step;
    const int pol =
        has_steps ? quadrant_polarity(*img_, cand_[static_cast<std::size_t>(at(ci, cj))].px.cast<double>(),
                                      dc, dr, own_steps)
                  : 0;
    sign[static_cast<std::size_t>(k)] = (ci + cj) % 2 == 0 ? pol : -pol;
  }
  int placements = 0, uncertain = 0, pi = 0, pj = 0;
  bool p_i_is_col = true;
  for (int orient = 0; orient < (rows == cols ? 1 : 2); ++orient) {
    const int w = orient == 0 ? cols : rows, h = orient == 0 ? rows : cols;
    for (int j = j0; j + h - 1 <= j1; ++j) {
      for (int i = i0; i + w - 1 <= i1; ++i) {
        int inside = 0, sum = 0, outside = 0;
        for (int k = 0; k < n; ++k) {
          const int ci = cells[static_cast<std::size_t>(k)][0], cj = cells[static_cast<std::size_t>(k)][1];
          if (ci >= i && ci < i + w && cj >= j && cj < j + h) {
            ++inside;
            sum += sign[static_cast<std::size_t>(k)];
          } else {
            ++outside;
          }
        }
        if (inside < w * h) continue;
        if (outside > kMaxStrayCells) {
          if (std::abs(sum) < w * h) continue;  // an L- or T-junction (or a wrong sign) in it
          const int board_sign = sum > 0 ? 1 : -1;
          int adjacent_x = 0;
          for (int k = 0; k < n; ++k) {
            const int ci = cells[static_cast<std::size_t>(k)][0], cj = cells[static_cast<std::size_t>(k)][1];
            const bool in = ci >= i && ci < i + w && cj >= j && cj < j + h;
            const bool next = ci >= i - 1 && ci <= i + w && cj >= j - 1 && cj <= j + h;
            // Only saddles the map found: a filled hole is a prediction, no evidence of a next row.
            const bool observed = cand_[static_cast<std::size_t>(at(ci, cj))].response > 0.0f;
            if (in || !next || !observed || sign[static_cast<std::size_t>(k)] != board_sign) continue;
            // An X-junction beside the placement is a next row only where the grid lines through it
            // run on away from the placement (grid_line_continues): clutter beside a board's margin
            // can make the junction look like an X (a bright monitor behind OpenCV's right08).
            Eigen::Vector2d dc, dr;
            if (steps(ci, cj, dc, dr)) {
              const Eigen::Vector2d p = cand_[static_cast<std::size_t>(at(ci, cj))].px.cast<double>();
              const bool lines = (ci >= i || grid_line_continues(*img_, p, -dc, dr)) &&
                                 (ci < i + w || grid_line_continues(*img_, p, dc, dr)) &&
                                 (cj >= j || grid_line_continues(*img_, p, -dr, dc)) &&
                                 (cj < j + h || grid_line_continues(*img_, p, dr, dc));
              if (!lines) continue;
            }
            ++adjacent_x;
          }
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
  if (placements == 0) {
    count_ = own_count;
    return 0;
  }
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
  grid_count_ = -1;
  usable_ = next_k_ = tried_ = 0;
  noise_ = noise;
  img_ = &img;
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
  usable_ = usable;
  next_k_ = 0;
  tried_ = 0;
  stamp_ = 0;
  rows_ = rows;
  cols_ = cols;
  if (usable + kMaxFilledHoles < rows * cols) return false;  // even with every hole the lattice may fill
  std::sort(order_.begin(), order_.begin() + usable, [&](int x, int y) {
    return cand_[static_cast<std::size_t>(x)].response > cand_[static_cast<std::size_t>(y)].response;
  });
  return find_next(out);
}

bool CoarseGridFinder::find_next(Eigen::Vector2f* out) {
  // Seeds from the strongest saddle down; a seed already in an earlier component (incomplete, or a
  // grid the fit refused) would only grow the same component again. The holes a returned grid
  // filled are its own: dropped before the next growth.
  if (grid_count_ >= 0) count_ = grid_count_;
  grid_count_ = -1;
  while (next_k_ < usable_ && tried_ < s_.max_seeds) {
    const int seed = order_[static_cast<std::size_t>(next_k_++)];
    if (cell_of_[static_cast<std::size_t>(seed)] >= 0) continue;
    ++tried_;
    const int before = count_;
    const int r = grow(seed, rows_, cols_, out);
    if (r > 0) grid_count_ = before;
    if (r != 0) {
      if (r < 0) next_k_ = usable_;  // a larger board or two placements: nothing is certain
      return r > 0;
    }
  }
  return false;
}

}  // namespace naneye::recon
