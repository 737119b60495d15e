// The sparse path's wider LK window up to lk_affine's widest (kMaxLkRadius): until 2026-12-06 the
// affine LK took at most 15 x 15, and SparseSettings::wide_radius 8-10 silently gave the narrow
// window's matches alone (the "8 breaks" of docs/scene.md). Each radius up to the cap must now be
// matched with (its points differ from the narrow window's and from each other's), and one beyond
// it is refused by name.
#include <gtest/gtest.h>

#include <stdexcept>

#include "naneye/recon/scene/sparse.hpp"
#include "scene_fixture.hpp"

namespace naneye::sparse_wide_cap_test {
namespace {

// The plane's valid points' right pixels with the given wider window (0: the narrow one alone).
std::vector<Eigen::Vector2d> right_pixels(int wide_radius) {
  const sim::TexturedPair& p = test::textured_pair("plane", false);
  recon::scene::SparseSettings s;
  s.wide_radius = wide_radius;
  recon::scene::SparseReconstructor sr(test::paper_d3(), s);
  recon::scene::SparseResult out;
  sr.reconstruct(sim::raw_view(p.left), sim::raw_view(p.right), out);
  std::vector<Eigen::Vector2d> px;
  for (const auto& q : out.points)
    if (q.valid()) px.push_back(q.right_px);
  return px;
}

// Points whose right pixel moved by more than 1e-6 px between two runs (same features: the ids and
// order depend on the left image only).
int moved(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  int n = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) n += (a[i] - b[i]).norm() > 1e-6;
  return n;
}

TEST(SparseWideWindow, EveryRadiusUpToTheCapIsMatchedWith) {
  const auto narrow = right_pixels(0), six = right_pixels(6), ten = right_pixels(recon::scene::kMaxLkRadius);
  ASSERT_EQ(narrow.size(), six.size());
  ASSERT_EQ(narrow.size(), ten.size());
  // The plane keeps ~99 % of its wider windows (sparse_wide.cpp): most points move.
  EXPECT_GT(moved(narrow, six), static_cast<int>(narrow.size()) / 2);
  EXPECT_GT(moved(narrow, ten), static_cast<int>(narrow.size()) / 2);
  EXPECT_GT(moved(six, ten), static_cast<int>(narrow.size()) / 2);
}

TEST(SparseWideWindow, BeyondTheCapIsRefused) {
  recon::scene::SparseSettings s;
  s.wide_radius = recon::scene::kMaxLkRadius + 1;
  try {
    recon::scene::SparseReconstructor sr(test::paper_d3(), s);
    ADD_FAILURE() << "made";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wide_radius 11 must be at most 10"), std::string::npos) << e.what();
  }
}

TEST(SparseWideWindow, ANarrowRadiusBelowOneIsRefused) {
  for (const int r : {0, -2}) {
    recon::scene::SparseSettings s;
    s.lk.radius = r;
    try {
      recon::scene::SparseReconstructor sr(test::paper_d3(), s);
      ADD_FAILURE() << "made with " << r;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("lk.radius " + std::to_string(r) + " must be at least 1 px"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace naneye::sparse_wide_cap_test
