// Stable feature ids across pairs (recon/scene/feature_ids.hpp): a point keeps its id while it moves
// a few pixels, a new view never inherits ids, and the sparse path carries them.
#include <gtest/gtest.h>

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

// b is a moved by (dx, dy): a feature of b whose point was a feature of a (within 1 px of where the
// move puts it) should carry its id; an inherited id whose a-feature is farther than 1.5 px from
// there is wrong.
Kept compare(const Frame& a, const Frame& b, double dx, double dy) {
  std::map<std::int64_t, const Feature*> by_id;
  for (std::size_t k = 0; k < a.features.size(); ++k) by_id[a.ids[k]] = &a.features[k];
  Kept out;
  for (std::size_t k = 0; k < b.features.size(); ++k) {
    const Feature& f = b.features[k];
    const double ux = f.u - dx, vy = f.v - dy;
    const bool had = std::any_of(a.features.begin(), a.features.end(),
                                 [&](const Feature& g) { return std::hypot(g.u - ux, g.v - vy) <= 1.0; });
    out.correspondences += had;
    const auto it = by_id.find(b.ids[k]);
    if (it == by_id.end()) continue;
    ++out.inherited;
    const bool right = std::hypot(it->second->u - ux, it->second->v - vy) <= 1.5;
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
  // A smooth hand-held move: 1-3 px per frame, sub-pixel, changing direction.
  const double steps[][2] = {{1.0, 0.0}, {1.5, 0.5}, {0.3, 2.2}, {-2.0, 1.0}, {-1.2, -2.6}};
  for (const auto& st : steps) {
    dx += st[0];
    dy += st[1];
    Frame cur{shifted(base, dx, dy), {}, {}};
    detect(det, cur);
    ids.assign(GrayView{reinterpret_cast<const float*>(cur.img.data), 250, 250}, cur.features, cur.ids);
    const Kept k = compare(prev, cur, st[0], st[1]);
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

}  // namespace
}  // namespace naneye
