// The processing step's settings and what it says of itself: the recon structs' own defaults, a
// check() that names naneyed's key, and a name that reports the triangulation configured.
#include <gtest/gtest.h>

#include "naneye/app/processor.hpp"

using namespace naneye;

namespace {

std::string name_of(const app::ProcessorSettings& s) {
  return std::string(app::make_processor(s)->name());
}

}  // namespace

TEST(Processor, NameReportsTheConfiguredTriangulation) {
  app::ProcessorSettings s;
  EXPECT_EQ(name_of(s), "board reconstruction (corners, niter2 + refinement, board pose)");  // the default
  s.reconstructor.reconstruction.method = recon::TriangulationMethod::dlt;
  EXPECT_EQ(name_of(s), "board reconstruction (corners, dlt, board pose)");
  s.reconstructor.reconstruction.method = recon::TriangulationMethod::niter2;
  EXPECT_EQ(name_of(s), "board reconstruction (corners, niter2, board pose)");
  s.reconstructor.reconstruction.method = recon::TriangulationMethod::midpoint;
  EXPECT_EQ(name_of(s), "board reconstruction (corners, midpoint, board pose)");
  s.mode = app::ReconMode::scene;
  EXPECT_EQ(name_of(s), "scene reconstruction (sparse features, dense depth map on a second thread)");
  s.threads = 1;
  EXPECT_EQ(name_of(s), "scene reconstruction (sparse features, dense depth map)");
  s.detect = false;
  EXPECT_EQ(name_of(s), "timing only (board.detect = false)");
}

TEST(Processor, SettingsDefaultToReconsAndCheckNamesTheKey) {
  const app::ProcessorSettings defaults;
  const recon::BoardGeometry paper;
  EXPECT_EQ(defaults.reconstructor.corners.board.rows, paper.rows);
  EXPECT_EQ(defaults.reconstructor.corners.board.cols, paper.cols);
  EXPECT_DOUBLE_EQ(defaults.reconstructor.corners.board.square_mm, paper.square_mm);
  EXPECT_TRUE(defaults.detect);
  EXPECT_EQ(defaults.mode, app::ReconMode::board);
  EXPECT_EQ(defaults.check(), "");

  auto s = defaults;
  s.reconstructor.corners.board.rows = 1;
  EXPECT_EQ(s.check().rfind("board.rows and cols: ", 0), 0u) << s.check();
  s = defaults;
  s.reconstructor.corners.board.rows = 9;
  EXPECT_EQ(s.check().rfind("board.rows, board.cols: at most 64", 0), 0u) << s.check();
  s = defaults;
  s.reconstructor.corners.board.square_mm = 0;
  EXPECT_EQ(s.check().rfind("board.square_mm: ", 0), 0u) << s.check();
  s = defaults;
  s.reconstructor.reconstruction.corner_sigma_px = 0;
  EXPECT_EQ(s.check().rfind("pipeline.corner_sigma_px: ", 0), 0u) << s.check();
  s = defaults;
  s.threads = 3;
  EXPECT_EQ(s.check(), "recon.threads: expected 1 or 2, got 3");
}

TEST(Processor, ReconModeNamesRoundTrip) {
  EXPECT_STREQ(app::to_string(app::ReconMode::board), "board");
  EXPECT_STREQ(app::to_string(app::ReconMode::scene), "scene");
  EXPECT_STREQ(app::to_string(app::ReconMode::both), "both");
}
