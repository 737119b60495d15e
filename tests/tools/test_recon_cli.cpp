// `naneye recon --json` on the bundled simulated captures, against their truth.json: every pair in
// stream order, every fully seen board found, no board where there is none or where it is cut, and
// the 3D figures of docs/reconstruction.md.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "run_cli.hpp"

using naneye::test::run_cli;
using nlohmann::json;

namespace {

struct Figures {
  int pairs = 0, found = 0, expected = 0, false_boards = 0;
  double tri_sq = 0, board_sq = 0, worst_board = 0;
  int n_tri = 0, n_board = 0;
  long long t0 = 0;
};

double dist(const json& a, const json& b) {
  double s = 0;
  for (int i = 0; i < 3; ++i) s += std::pow(a[i].get<double>() - b[i].get<double>(), 2);
  return std::sqrt(s);
}

Figures run_capture(const std::string& name, const std::string& calib, const std::string& square,
                    const std::string& params = "") {
  const std::string dir = std::string(NANEYE_TEST_DATA_DIR) + "/" + name;
  const auto r = run_cli("recon --json --calib " + std::string(NANEYE_SOURCE_DIR) + "/config/calib/" + calib +
                         " --square-mm " + square + " --input " + dir + "/capture.raw" + params);
  EXPECT_EQ(r.exit_code, 0);
  std::ifstream tf(dir + "/truth.json");
  const json truth = json::parse(tf);
  const auto& tpairs = truth["pairs"];
  Figures f;
  std::istringstream lines(r.out);
  std::string line;
  while (std::getline(lines, line)) {
    const json res = json::parse(line);
    if (res.contains("summary")) {  // the last line: pairs per failure reason
      EXPECT_EQ(res["summary"]["pairs"].get<int>(), f.pairs);
      EXPECT_EQ(res["summary"]["found"].get<int>(), f.found);
      continue;
    }
    const int i = f.pairs++;
    if (i >= static_cast<int>(tpairs.size())) break;
    const json& t = tpairs[static_cast<std::size_t>(i)];
    EXPECT_EQ(res["pair"].get<int>(), i);
    // Sensor time runs from the camera's own clock; the truth counts from the stream's first record.
    if (i == 0) f.t0 = res["t_left_ns"].get<long long>() - t["t_left_ns"].get<long long>();
    EXPECT_NEAR(res["t_left_ns"].get<long long>() - f.t0, t["t_left_ns"].get<long long>(), 1);
    EXPECT_NEAR(res["t_right_ns"].get<long long>() - f.t0, t["t_right_ns"].get<long long>(), 1);
    const bool in_view = t["board_in_view"].get<bool>();
    f.expected += in_view;
    if (!res["board_found"].get<bool>()) {
      EXPECT_TRUE(res["board"].is_null());
      EXPECT_TRUE(res["metrics"].is_null());
      EXPECT_TRUE(res["failure"].is_object());  // why: the pair's outcome and each eye's reason
      continue;
    }
    ++f.found;
    if (!in_view) {
      ++f.false_boards;
      continue;
    }
    // The 9 x 7 board looks the same turned by 180 degrees: our ids match the truth's either as they
    // are or reversed, consistently for the whole board.
    const auto& pts = res["points"];
    const int n = static_cast<int>(pts.size());
    double direct = 0, reversed = 0;
    for (int k = 0; k < n; ++k) {
      if (pts[k]["xyz_board_mm"].is_null()) continue;
      direct += dist(pts[k]["xyz_board_mm"], t["corners_xyz_mm"][k]);
      reversed += dist(pts[k]["xyz_board_mm"], t["corners_xyz_mm"][n - 1 - k]);
    }
    const bool rev = reversed < direct;
    for (int k = 0; k < n; ++k) {
      const json& truth_xyz = t["corners_xyz_mm"][rev ? n - 1 - k : k];
      if (!pts[k]["valid"].get<bool>()) {
        // A corner that could not be used carries no coordinates at all.
        EXPECT_TRUE(pts[k]["xyz_mm"].is_null());
        continue;
      }
      const double eb = dist(pts[k]["xyz_board_mm"], truth_xyz);
      f.board_sq += eb * eb;
      f.worst_board = std::max(f.worst_board, eb);
      ++f.n_board;
      const double et = dist(pts[k]["xyz_mm"], truth_xyz);
      f.tri_sq += et * et;
      ++f.n_tri;
    }
  }
  EXPECT_EQ(f.pairs, static_cast<int>(tpairs.size()));
  std::printf(
      "%s: %d pairs, %d boards in view, %d found, %d false; triangulated 3D RMS %.3f mm, board 3D RMS "
      "%.4f mm (worst %.4f)\n",
      name.c_str(), f.pairs, f.expected, f.found, f.false_boards, std::sqrt(f.tri_sq / std::max(1, f.n_tri)),
      std::sqrt(f.board_sq / std::max(1, f.n_board)), f.worst_board);
  return f;
}

}  // namespace

TEST(ReconCli, Dataset3MonoCaptureAgainstTruth) {
  const Figures f = run_capture("sim-d3-mono", "paper-d3.yaml", "5.99");
  EXPECT_EQ(f.found, f.expected);
  EXPECT_EQ(f.false_boards, 0);
  EXPECT_LT(std::sqrt(f.tri_sq / f.n_tri), 1.5);
  EXPECT_LT(std::sqrt(f.board_sq / f.n_board), 0.05);
}

TEST(ReconCli, Dataset3BayerCaptureAgainstTruth) {
  const Figures f = run_capture("sim-d3-bayer", "paper-d3.yaml", "5.99", "?color=grbg");
  EXPECT_EQ(f.found, f.expected);
  EXPECT_EQ(f.false_boards, 0);
  EXPECT_LT(std::sqrt(f.board_sq / f.n_board), 0.05);
}

TEST(ReconCli, CutAndAbsentBoardsAreNotFound) {
  const Figures f = run_capture("sim-d1-cut", "paper-d1.yaml", "2.25");
  EXPECT_EQ(f.false_boards, 0);
  EXPECT_EQ(f.found, f.expected);
}

TEST(ReconCli, BadInputIsAClearError) {
  const auto r = run_cli(
      std::string("recon --calib ") + NANEYE_SOURCE_DIR + "/config/calib/paper-d3.yaml --input ftp://nowhere",
      true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("ftp"), std::string::npos) << r.out;
}
