// Defect pixels on a board edge: the luminance's repair cannot see them (such a pixel lies between
// its neighbours' values), so the saddle fit drops them as outliers (fit_saddle_fast) instead of
// rejecting the corner, and the corner stays as accurate as on the clean frame.
#include <gtest/gtest.h>

#include <algorithm>

#include "corner_test_util.hpp"

namespace naneye::recon {
namespace {

TEST(EdgeDefects, StuckPixelsOnEdgesAreDroppedNotFatal) {
  const StereoRig& rig = test::paper_d3();
  std::mt19937_64 rng(41);
  const sim::RenderedPair p = test::render(false, test::random_pose(rng, 66, 74, 20, 2), 4100);
  const std::vector<Eigen::Vector2d>& truth = p.truth.left_px;
  cv::Mat img = p.left.clone();
  // On three corners' row edges, 3 px out: the pixel takes the brightest of its 8 neighbours (a
  // stuck pixel at the white level next to the white square): off by about half the contrast.
  std::vector<int> hit;
  for (const int id : {9, 20, 35}) {
    const Eigen::Vector2d along =
        (truth[static_cast<std::size_t>(id + 1)] - truth[static_cast<std::size_t>(id)]).normalized();
    const Eigen::Vector2d q = truth[static_cast<std::size_t>(id)] + 3.0 * along;
    // Of the pixels next to that edge point, the one furthest below its brightest neighbour.
    int x = 0, y = 0, best = -1;
    std::uint16_t brightest = 0;
    for (int oy = -1; oy <= 1; ++oy) {
      for (int ox = -1; ox <= 1; ++ox) {
        const int cx = static_cast<int>(std::lround(q.x())) + ox,
                  cy = static_cast<int>(std::lround(q.y())) + oy;
        std::uint16_t b = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (dx || dy) b = std::max(b, img.at<std::uint16_t>(cy + dy, cx + dx));
        if (b - img.at<std::uint16_t>(cy, cx) > best) {
          best = b - img.at<std::uint16_t>(cy, cx);
          x = cx;
          y = cy;
          brightest = b;
        }
      }
    }
    ASSERT_GT(best, 150) << "no pixel on the edge";
    img.at<std::uint16_t>(y, x) = brightest;
    hit.push_back(id);
  }
  CornerDetector det(rig.left);
  CornerResult clean, defective;
  ASSERT_TRUE(det.detect_full(sim::raw_view(p.left, false), clean));
  ASSERT_TRUE(det.detect_full(sim::raw_view(img, false), defective)) << to_string(det.last_failure());
  const bool turned = test::best_turn(defective, truth);
  for (const int id : hit) {
    const int i = turned ? defective.count - 1 - id : id;
    const Corner& c = defective.corners[static_cast<std::size_t>(i)];
    const Corner& k = clean.corners[static_cast<std::size_t>(i)];
    EXPECT_LT((c.px - truth[static_cast<std::size_t>(id)]).norm(), 0.05) << "corner " << id;
    EXPECT_LT((c.px - k.px).norm(), 0.03) << "corner " << id;
    EXPECT_EQ(c.flags & kCornerFitPoor, 0) << "corner " << id;
  }
}

}  // namespace
}  // namespace naneye::recon
