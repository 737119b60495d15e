#include <gtest/gtest.h>

#include "naneye/app/processor.hpp"
#include "naneye/app/result_json.hpp"

using namespace naneye;

namespace {

recon::PairResult sample_result() {
  recon::PairResult r;
  r.pair = 17;
  r.t_left_ns = 123456789;
  r.t_right_ns = 126000000;
  r.board_found = true;
  r.point_count = 2;
  auto& p = r.points[0];
  p.id = 5, p.row = 0, p.col = 5, p.valid = true;
  p.left_px = {10.25, 20.5};
  p.right_px = {11.75, 20.0};
  p.xyz_mm = {1.5, -2.25, 70.125};
  p.depth_sigma_mm = 0.75;
  p.xyz_board_mm = {1.5, -2.25, 70.0};
  auto& q = r.points[1];
  q.id = 6, q.row = 0, q.col = 6, q.valid = false;
  q.left_px = {240.0, 3.0};
  q.right_px = {241.0, 3.5};
  recon::BoardResult b;
  b.rotation << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  b.translation_mm = {-3, 4, 70};
  b.normal = {0, 0, -1};
  b.distance_mm = 70;
  b.rms_px = 0.04;
  r.board = b;
  r.metrics = recon::MetricsResult{0.3, 0.2, 0.05};
  return r;
}

}  // namespace

TEST(ResultJson, HasTheIssue5Shape) {
  const auto j = app::result_to_json(sample_result());
  EXPECT_EQ(j.at("pair"), 17);
  EXPECT_EQ(j.at("t_left_ns"), 123456789);
  EXPECT_EQ(j.at("t_right_ns"), 126000000);
  EXPECT_EQ(j.at("board_found"), true);
  ASSERT_EQ(j.at("points").size(), 2u);
  const auto& p = j.at("points")[0];
  EXPECT_EQ(p.at("id"), 5);
  EXPECT_EQ(p.at("left_px"), nlohmann::json({10.25, 20.5}));
  EXPECT_EQ(p.at("xyz_mm"), nlohmann::json({1.5, -2.25, 70.125}));
  EXPECT_EQ(p.at("depth_sigma_mm"), 0.75);
  EXPECT_EQ(p.at("valid"), true);
  const auto& q = j.at("points")[1];
  EXPECT_TRUE(q.at("xyz_mm").is_null());
  EXPECT_TRUE(q.at("xyz_board_mm").is_null());
  EXPECT_TRUE(q.at("depth_sigma_mm").is_null());
  EXPECT_EQ(q.at("valid"), false);
  // Row-major rotation: the second row is (1, 0, 0).
  EXPECT_EQ(j.at("board").at("rotation")[1], nlohmann::json({1.0, 0.0, 0.0}));
  EXPECT_EQ(j.at("board").at("distance_mm"), 70.0);
  EXPECT_EQ(j.at("metrics").at("planarity_mm"), 0.3);
}

TEST(ResultJson, BoardAndMetricsAreNullWithoutABoard) {
  recon::PairResult r;
  r.pair = 3;
  const auto j = app::result_to_json(r);
  EXPECT_TRUE(j.at("board").is_null());
  EXPECT_TRUE(j.at("metrics").is_null());
  EXPECT_TRUE(j.at("points").is_array());
  EXPECT_TRUE(j.at("points").empty());
}

TEST(ResultJson, RoundTripsThroughText) {
  const auto r = sample_result();
  const auto back = app::result_from_json(nlohmann::json::parse(app::result_to_json(r).dump()));
  EXPECT_EQ(back.pair, r.pair);
  EXPECT_EQ(back.t_right_ns, r.t_right_ns);
  ASSERT_EQ(back.point_count, 2);
  EXPECT_EQ(back.points[0].xyz_mm, r.points[0].xyz_mm);
  EXPECT_EQ(back.points[0].left_px, r.points[0].left_px);
  EXPECT_FALSE(back.points[1].valid);
  EXPECT_EQ(back.points[1].right_px, r.points[1].right_px);
  ASSERT_TRUE(back.board.has_value());
  EXPECT_EQ(back.board->rotation, r.board->rotation);
  EXPECT_EQ(back.board->translation_mm, r.board->translation_mm);
  ASSERT_TRUE(back.metrics.has_value());
  EXPECT_EQ(back.metrics->reprojection_px, 0.05);
}

TEST(ResultJson, EachEyesReferenceCheckIsShownAsTheSourceReportedIt) {
  // A V4L2 frame was "reference_ok" without any check; now a frame says what was checked, and the
  // result carries it: passed, failed, or not_checked (never "passed" for a frame nobody looked at).
  auto pair = std::make_unique<driver::StereoPair>();  // 250 kB of pixels: not on the stack
  pair->left.reference = driver::ReferenceStatus::not_checked;
  pair->right.reference = driver::ReferenceStatus::failed;
  recon::PairResult r;
  app::fill_pair_identity(*pair, r);
  const auto j = app::result_to_json(r);
  EXPECT_EQ(j.at("reference"), nlohmann::json({{"left", "not_checked"}, {"right", "failed"}}));
  const auto back = app::result_from_json(j);
  EXPECT_STREQ(back.reference_left, "not_checked");
  EXPECT_STREQ(back.reference_right, "failed");
  // A result that never came from a source says nothing.
  EXPECT_EQ(app::result_to_json(recon::PairResult{}).at("reference"),
            nlohmann::json({{"left", nullptr}, {"right", nullptr}}));
  auto bad = j;
  bad["reference"]["left"] = "ok";
  EXPECT_THROW(app::result_from_json(bad), std::invalid_argument);
}

TEST(ResultJson, RefusesMalformedObjects) {
  auto j = app::result_to_json(sample_result());
  j["points"][0]["xyz_mm"] = {1.0, 2.0};
  EXPECT_THROW(app::result_from_json(j), nlohmann::json::exception);
  auto k = app::result_to_json(sample_result());
  k.erase("pair");
  EXPECT_THROW(app::result_from_json(k), nlohmann::json::exception);
}
