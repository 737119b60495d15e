// Stable feature ids across pairs (recon/scene/feature_ids.hpp): a point keeps its id while it moves
// a few pixels, a new view never inherits ids, and the sparse path carries them.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

#include "naneye/recon/scene/feature_ids.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

using recon::scene::Feature;
using recon::scene::FeatureDetector;
using recon::scene::FeatureIds;
using recon::scene::GrayView;

// The left luminance of a textured render, as the sparse path sees it.
cv::Mat1f left_luma(const std::string& preset, std::uint64_t seed) {
  const auto& p = test::textured_pair(preset, false, seed);
  recon::scene::SparseReconstructor sr(test::paper_d3());
  sr.load_luma(sim::raw_view(p.left, false), sim::raw_view(p.right, false));
  return cv::Mat1f(250, 250, const_cast<float*>(sr.luma().left.data())).clone();
}

// Moves the image content by (dx, dy) px (bicubic), replicating the border.
cv::Mat1f shifted(const cv::Mat1f& img, double dx, double dy) {
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::Mat1f out;
  cv::warpAffine(img, out, M, img.size(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return out;
}

struct Frame {
  cv::Mat1f img;
  std::vector<Feature> features;
  std::vector<std::int64_t> ids;
};

// Features inside a 12 px margin (every window and every move stays in the image).
void detect(FeatureDetector& det, Frame& f) {
  std::vector<std::uint8_t> usable(250 * 250, 0);
  for (int r = 12; r < 238; ++r)
    for (int c = 12; c < 238; ++c) usable[static_cast<std::size_t>(r) * 250 + c] = 1;
  f.features.clear();
  f.features.reserve(1536);
  det.detect(GrayView{reinterpret_cast<const float*>(f.img.data), 250, 250}, usable.data(), 1.0, f.features);
  f.ids.assign(f.features.size(), -1);
}

struct Kept {
  int correspondences = 0, same_id = 0, wrong = 0, inherited = 0;
};

// Where each id began, in the base image's coordinates (a pixel of a frame moved by (dx, dy) shows
// the base image's point (u - dx, v - dy)): an id is one scene point while it lives.
using Origins = std::map<std::int64_t, std::pair<double, double>>;

// b is a moved by (dx, dy), the base by (bx, by) in all: a feature of b whose point was a feature of
// a (within 1 px of where the move puts it) should carry its id; an inherited id is wrong when b's
// pixel lies farther than 1.5 px from the point the id began at (the pixel centre nearest the id's
// point is within 0.71 px of it; the motion's estimate adds the rest). New ids' origins are noted.
Kept compare(const Frame& a, const Frame& b, double dx, double dy, double bx, double by, Origins& origin) {
  std::set<std::int64_t> in_a(a.ids.begin(), a.ids.end());
  Kept out;
  for (std::size_t k = 0; k < b.features.size(); ++k) {
    const Feature& f = b.features[k];
    const double ux = f.u - dx, vy = f.v - dy;
    const bool had = std::any_of(a.features.begin(), a.features.end(),
                                 [&](const Feature& g) { return std::hypot(g.u - ux, g.v - vy) <= 1.0; });
    out.correspondences += had;
    if (!in_a.count(b.ids[k])) {
      origin[b.ids[k]] = {f.u - bx, f.v - by};
      continue;
    }
    ++out.inherited;
    const auto& [ox, oy] = origin.at(b.ids[k]);
    const bool right = std::hypot(f.u - bx - ox, f.v - by - oy) <= 1.5;
    out.same_id += right && had;
    out.wrong += !right;
  }
  return out;
}

TEST(FeatureIds, FollowPointsThatMoveAndNeverReuseAnId) {
  FeatureDetector det(250, 250, {});
  FeatureIds ids(250, 250, 1536);
  const cv::Mat1f base = left_luma("plane", 5);
  double dx = 0, dy = 0;
  Frame prev{base.clone(), {}, {}};
  detect(det, prev);
  ids.assign(GrayView{reinterpret_cast<const float*>(prev.img.data), 250, 250}, prev.features, prev.ids);
  std::set<std::int64_t> first(prev.ids.begin(), prev.ids.end());
  EXPECT_EQ(first.size(), prev.ids.size());  // all distinct
  Origins origin;
  for (std::size_t k = 0; k < prev.features.size(); ++k)
    origin[prev.ids[k]] = {prev.features[k].u, prev.features[k].v};
  // A smooth hand-held move: 1-3 px per frame, sub-pixel, changing direction.
  const double steps[][2] = {{1.0, 0.0}, {1.5, 0.5}, {0.3, 2.2}, {-2.0, 1.0}, {-1.2, -2.6}};
  for (const auto& st : steps) {
    dx += st[0];
    dy += st[1];
    Frame cur{shifted(base, dx, dy), {}, {}};
    detect(det, cur);
    ids.assign(GrayView{reinterpret_cast<const float*>(cur.img.data), 250, 250}, cur.features, cur.ids);
    const Kept k = compare(prev, cur, st[0], st[1], dx, dy, origin);
    std::printf("move (%+.1f, %+.1f): %4zu features, %4d had a match, %4d kept their id, %d wrong\n", st[0],
                st[1], cur.features.size(), k.correspondences, k.same_id, k.wrong);
    // Measured: 82-95 % kept, 0 wrong (the rest fail the sub-pixel verification or lose a tie).
    EXPECT_GE(k.same_id, 0.8 * k.correspondences);
    EXPECT_LE(k.wrong, 0.005 * k.inherited + 1);
    std::set<std::int64_t> distinct(cur.ids.begin(), cur.ids.end());
    EXPECT_EQ(distinct.size(), cur.ids.size());
    prev = std::move(cur);
  }
  // Another view of another surface: nothing to inherit.
  Frame other{left_luma("sphere", 9), {}, {}};
  detect(det, other);
  ids.assign(GrayView{reinterpret_cast<const float*>(other.img.data), 250, 250}, other.features, other.ids);
  const std::int64_t last = *std::max_element(prev.ids.begin(), prev.ids.end());
  const auto reused =
      std::count_if(other.ids.begin(), other.ids.end(), [&](std::int64_t id) { return id <= last; });
  EXPECT_LE(reused, static_cast<long>(0.01 * static_cast<double>(other.ids.size())));
  // And after reset() every id is new.
  ids.reset();
  Frame again{base.clone(), {}, {}};
  detect(det, again);
  ids.assign(GrayView{reinterpret_cast<const float*>(again.img.data), 250, 250}, again.features, again.ids);
  const std::int64_t before = *std::max_element(other.ids.begin(), other.ids.end());
  EXPECT_GT(*std::min_element(again.ids.begin(), again.ids.end()), before);
}

TEST(FeatureIds, SparsePathKeepsEveryIdOnTheSamePairAndSpreadsItsPoints) {
  const auto& p = test::textured_pair("height", false);
  recon::scene::SparseReconstructor sr(test::paper_d3());
  recon::scene::SparseResult a, b;
  sr.reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), a);
  sr.reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), b);
  ASSERT_EQ(a.points.size(), b.points.size());
  // Every valid point keeps its id (a window with no texture, e.g. saturated, has nothing to
  // compare: such a feature gets a new id, and it is never a valid point).
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    if (a.points[k].valid()) {
      EXPECT_EQ(a.points[k].id, b.points[k].id) << k;
    }
  }
  // Matching stops at max_points valid points, and those cover the view: every quarter of the image
  // holds at least a sixth of them (coarse-to-fine order, not raster order).
  EXPECT_LE(b.valid_count, sr.settings().max_points);
  int quarter[4] = {0, 0, 0, 0};
  for (const auto& q : b.points)
    if (q.valid()) ++quarter[(q.left_px.x() >= 125 ? 1 : 0) + (q.left_px.y() >= 125 ? 2 : 0)];
  for (int k = 0; k < 4; ++k) EXPECT_GE(quarter[k], b.valid_count / 6) << "quarter " << k;
}

// Where matching stops at max_points, the features it tried are the coarse lattice (every 2nd cell
// in both directions: the view covered) and then the strongest of the rest by lambda_min, i.e. the
// most precise (SparseReconstructor::reconstruct): not the rest's top rows, as in raster order.
TEST(FeatureIds, SparsePathTriesTheLatticeThenTheStrongestWhereItStops) {
  const auto& p = test::textured_pair("plane", false);
  recon::scene::SparseReconstructor sr(test::paper_d3());
  recon::scene::SparseResult out;
  sr.reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), out);
  std::vector<Feature> all;
  all.reserve(static_cast<std::size_t>(sr.settings().max_features));
  FeatureDetector det(250, 250, sr.settings().features);
  det.detect(sr.luma().left_view(), sr.usable(0).data(), out.noise_sigma_dn, all);
  ASSERT_EQ(out.valid_count, sr.settings().max_points);
  ASSERT_LT(out.points.size(), all.size() * 3 / 4);  // stopped well before the last feature
  std::set<std::pair<int, int>> tried;
  for (const auto& q : out.points)
    tried.insert(
        {static_cast<int>(std::lround(q.left_px.x())), static_cast<int>(std::lround(q.left_px.y()))});
  const int cell = sr.settings().features.cell_px;
  float weakest_tried = std::numeric_limits<float>::infinity(), strongest_left = 0;
  int rest_tried = 0;
  for (const Feature& f : all) {
    const bool lattice = (f.u / cell) % 2 == 0 && (f.v / cell) % 2 == 0;
    const bool was_tried = tried.count({f.u, f.v}) > 0;
    if (lattice) {
      EXPECT_TRUE(was_tried) << f.u << ", " << f.v;
    } else if (was_tried) {
      weakest_tried = std::min(weakest_tried, f.min_eig);
      ++rest_tried;
    } else {
      strongest_left = std::max(strongest_left, f.min_eig);
    }
  }
  EXPECT_GT(rest_tried, 50);
  EXPECT_GE(weakest_tried, strongest_left);
}

// A hand-held sequence at camera rate (62 fps, sim::handheld_camera_pose): how long ids live and
// whether one id stays one scene point. Per frame the valid points whose id was a valid point the
// frame before ("carried"); per id living >= 10 frames, how far apart the surface points it gave at
// its first and last frame are (the scene's frame, in pixels at their depth: Z / 216 mm a pixel).
struct SequenceFigures {
  double carried = 0, mean_life = 0, drift_px = 0;
  int long_tracks = 0;
};

struct SequenceFrame {
  sim::Pose camera;
  cv::Mat left, right;
};

// The frames of a preset seen along the trajectory, rendered once per test binary (no truth needed:
// the drift is measured in the scene's frame from the points themselves).
const std::vector<SequenceFrame>& sequence(const std::string& preset, int frames) {
  static std::map<std::pair<std::string, int>, std::vector<SequenceFrame>> cache;
  auto& seq = cache[{preset, frames}];
  if (!seq.empty()) return seq;
  const auto scene = *sim::textured_preset(preset);
  for (int k = 0; k < frames; ++k) {
    SequenceFrame f{sim::handheld_camera_pose(scene.light_reference_mm, k / 62.0), {}, {}};
    sim::Rng rng(1000 + static_cast<std::uint64_t>(k));
    test::textured_renderer(false).render_frames(sim::seen_from(scene, f.camera), rng, f.left, f.right);
    seq.push_back(std::move(f));
  }
  return seq;
}

SequenceFigures follow(const std::string& preset, bool keep_tracked, int frames) {
  recon::scene::SparseSettings s;
  s.ids.keep_tracked = keep_tracked;
  recon::scene::SparseReconstructor sr(test::paper_d3(), s);
  recon::scene::SparseResult out;
  std::set<std::int64_t> prev, cur;
  std::map<std::int64_t, int> life;
  std::map<std::int64_t, std::pair<Eigen::Vector3d, Eigen::Vector3d>> ends;  // first, last (scene frame)
  long carried = 0, total = 0;
  int k = 0;
  for (const SequenceFrame& frame : sequence(preset, frames)) {
    const sim::Pose& pose = frame.camera;
    sr.reconstruct(sim::raw_view(frame.left, false), sim::raw_view(frame.right, false), out);
    cur.clear();
    for (const auto& q : out.points) {
      if (!q.valid()) continue;
      cur.insert(q.id);
      ++life[q.id];
      const Eigen::Vector3d x = pose.R * q.X + pose.t;
      const auto [it, fresh] = ends.try_emplace(q.id, x, x);
      it->second.second = x;
      if (k > 0) {
        ++total;
        carried += prev.count(q.id);
      }
    }
    prev.swap(cur);
    ++k;
  }
  SequenceFigures f;
  f.carried = static_cast<double>(carried) / static_cast<double>(std::max(1L, total));
  for (const auto& [id, n] : life) {
    f.mean_life += n;
    if (n < 10) continue;
    const auto& [a, b] = ends.at(id);
    f.drift_px += (b - a).norm() / (0.5 * (a.z() + b.z()) / 216.0);
    ++f.long_tracks;
  }
  f.mean_life /= static_cast<double>(std::max<std::size_t>(1, life.size()));
  f.drift_px /= std::max(1, f.long_tracks);
  std::printf(
      "%-6s keep_tracked %d: carried %.3f, mean life %.1f frames, %d ids >= 10 frames drift %.2f px\n",
      preset.c_str(), keep_tracked, f.carried, f.mean_life, f.long_tracks, f.drift_px);
  return f;
}

// FeatureIds::keep_tracked: each cell's strongest pixel moves from spot to spot of the texture as
// the image moves, and every move ended an id. Measured over 30 frames (2026-12-07): plane carried
// 0.82 -> 0.95, mean life 4.9 -> 12.9 frames; drift 0.87 -> 0.89 px (the floor: the pixel centre
// reported is within 0.71 px of the id's point, and the depth's own error). Before the ids carried
// their sub-pixel point, the chained roundings walked: 2.9 px over the same tracks. 14 frames here.
TEST(FeatureIds, AHandHeldSequenceKeepsItsIdsOnTheirPoints) {
  const SequenceFigures kept = follow("plane", true, 14), fresh = follow("plane", false, 14);
  EXPECT_GE(kept.carried, 0.9);
  EXPECT_LT(fresh.carried, kept.carried - 0.05);
  EXPECT_GT(kept.mean_life, 1.5 * fresh.mean_life);
  ASSERT_GE(kept.long_tracks, 200);
  EXPECT_LE(kept.drift_px, 1.5);
}

// A cut: after frames of one scene, a pair of another. Nothing follows over (the motion there is a
// chance median at best, and keep_tracked's patch test refuses it): the features are those a fresh
// reconstructor detects, and every id is new.
TEST(FeatureIds, ACutToAnotherSceneKeepsNothing) {
  recon::scene::SparseReconstructor followed(test::paper_d3()), fresh(test::paper_d3());
  recon::scene::SparseResult a, b;
  for (const SequenceFrame& f : sequence("plane", 3))
    followed.reconstruct(sim::raw_view(f.left, false), sim::raw_view(f.right, false), a);
  ASSERT_GT(a.valid_count, 400);
  const std::int64_t last =
      std::max_element(a.points.begin(), a.points.end(), [](const auto& x, const auto& y) {
        return x.id < y.id;
      })->id;
  const auto& p = test::textured_pair("sphere", false);
  followed.reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), a);
  fresh.reconstruct(sim::raw_view(p.left, false), sim::raw_view(p.right, false), b);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (std::size_t k = 0; k < a.points.size(); ++k) {
    EXPECT_EQ(a.points[k].left_px, b.points[k].left_px) << k;
    EXPECT_GT(a.points[k].id, last) << k;
  }
}

}  // namespace
}  // namespace naneye
