// `naneye study --preset paper --reduced`: the accuracy report a user regenerates, on the reduced set
// (Dataset 3, a few views): every table of the paper's study is there with finite numbers, the physics
// shows through them (the polynomial model beats one division parameter; the board pose beats
// triangulation), and the plots are real PNGs.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "run_cli.hpp"

using naneye::test::run_cli;

namespace {

struct Row {
  double P, D, R, E;
};

std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string c;
  while (std::getline(ss, c, '|')) {
    const auto b = c.find_first_not_of(' '), e = c.find_last_not_of(' ');
    out.push_back(b == std::string::npos ? "" : c.substr(b, e - b + 1));
  }
  return out;  // out[0] is the empty text before the first '|'
}

double number(const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0' ? v : NAN;
}

class StudyCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/naneye-study-XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    const auto r = run_cli("study --preset paper --reduced --out-dir " + dir_.string(), true);
    exit_code_ = r.exit_code;
    output_ = r.out;
    std::ifstream f(dir_ / "accuracy.md");
    std::stringstream ss;
    ss << f.rdbuf();
    report_ = ss.str();
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // The summary table's row of `method` for Dataset 3.
  static Row summary(const std::string& method, const std::string& dataset = "paper-d3") {
    std::istringstream in(report_);
    std::string line;
    while (std::getline(in, line)) {
      const auto c = cells(line);
      if (c.size() >= 8 && c[1] == dataset && c[2] == method)
        return {number(c[3]), number(c[4]), number(c[5]), number(c[6])};
    }
    ADD_FAILURE() << "no summary row for " << method;
    return {NAN, NAN, NAN, NAN};
  }

  static inline std::filesystem::path dir_;
  static inline int exit_code_ = -1;
  static inline std::string output_, report_;
};

TEST_F(StudyCli, WritesEveryTableOfThePaper) {
  ASSERT_EQ(exit_code_, 0) << output_;
  for (const char* heading :
       {"## Summary", "### Baseline", "### Division model with triangulation",
        "### Division model with plane sweep", "### Normalized division: undistort",
        "### Normalized division: triangulate the distorted points", "## The six-point comparison",
        "## Cross-validation", "## Where we differ from the paper",
        "naneye study --preset paper --out-dir docs"}) {
    EXPECT_NE(report_.find(heading), std::string::npos) << heading;
  }
  // Each per-plane table: five planes and the mean, the paper's own figures beside ours.
  std::size_t planes = 0, pos = 0;
  while ((pos = report_.find("| Plane 1 |", pos)) != std::string::npos) ++planes, ++pos;
  EXPECT_EQ(planes, 5u);
  EXPECT_NE(report_.find("| Plane 1 | 2.718 / 1.267 / 0.077 |"), std::string::npos);  // the paper's baseline
  EXPECT_NE(report_.find("| Plane 1 | 5.806 / 2.013 / 1.512 |"), std::string::npos);  // its division Plane 1
}

TEST_F(StudyCli, SummaryNumbersAreFiniteAndShowThePhysics) {
  ASSERT_EQ(exit_code_, 0) << output_;
  const Row tri = summary("polynomial, triangulated (ours: niter2 + refinement)");
  const Row dlt = summary("polynomial, exact undistortion + DLT");
  const Row board = summary("polynomial, board pose (ours)");
  const Row div = summary("division, image centre + DLT");
  const Row sweep = summary("division, image centre + plane sweep");
  const Row ntri = summary("division, normalized + DLT");
  const Row ndir = summary("division, normalized, Eq. 10 direct (one SVD)");
  for (const Row& r : {tri, dlt, board, div, sweep, ntri, ndir}) {
    EXPECT_TRUE(std::isfinite(r.P) && std::isfinite(r.D) && std::isfinite(r.R) && std::isfinite(r.E));
  }
  // Corners at ~0.05 px and a 1 mm baseline: millimetres of 3D error at 70 mm when triangulated (paper
  // Eq. 2), an order of magnitude less when the board is fitted to both eyes.
  EXPECT_GT(tri.E, 0.1);
  EXPECT_LT(tri.E, 5.0);
  EXPECT_LT(board.E, tri.E / 5);
  // With a classic detector's corner noise (0.2 px) the triangulated error grows in proportion (paper
  // Eq. 2: depth error is linear in the disparity error) to the paper's millimetres; the board pose keeps
  // its lead.
  const std::string noisy = "paper-d3 + 0.2 px corner noise";
  const Row tri_noisy = summary("polynomial, triangulated (ours: niter2 + refinement)", noisy);
  const Row board_noisy = summary("polynomial, board pose (ours)", noisy);
  EXPECT_GT(tri_noisy.E, 5 * tri.E);
  EXPECT_GT(tri_noisy.D, 0.5);
  EXPECT_LT(board_noisy.E, tri_noisy.E / 5);
  // One division parameter cannot follow the lens: every division variant is further from the truth than
  // the polynomial with the same corners.
  for (const Row& r : {div, sweep, ntri, ndir}) EXPECT_GT(r.E, tri.E);
  // The OpenCV user path (classic corners, ~0.1-0.2 px) lands several times further from the truth than
  // our triangulation of the same renders.
  const Row ocv =
      summary("OpenCV path (findChessboardCorners + cornerSubPix, undistortPoints, triangulatePoints)");
  EXPECT_TRUE(std::isfinite(ocv.E) && std::isfinite(ocv.R));
  EXPECT_GT(ocv.E, 2 * tri.E);
  // The paper: the plane sweep "as it was applied" is equivalent to triangulation.
  EXPECT_NEAR(sweep.E, div.E, 0.05 * div.E);
}

TEST_F(StudyCli, SixPointsInTheOuterFieldBreakTheDivisionModel) {
  ASSERT_EQ(exit_code_, 0) << output_;
  const auto at = report_.find("**outer field");
  ASSERT_NE(at, std::string::npos);
  std::istringstream in(report_.substr(at));
  std::string line;
  std::map<std::string, double> D, R_true;
  while (std::getline(in, line) && D.size() < 5) {
    const auto c = cells(line);
    if (c.size() >= 7 && std::isfinite(number(c[4]))) {
      D[c[1]] = number(c[4]);
      R_true[c[1]] = number(c[6]);
    }
  }
  ASSERT_EQ(D.size(), 5u);
  const double poly = D.at("polynomial, exact undistortion + DLT");
  EXPECT_LT(poly, 1e-6);  // noise-free: the polynomial path is exact
  EXPECT_GT(D.at("division, image centre + DLT"), 1.0);
  EXPECT_GT(R_true.at("division, image centre + DLT"), 1.0);
}

TEST_F(StudyCli, PlotsArePngsOfTheDocumentedSize) {
  ASSERT_EQ(exit_code_, 0) << output_;
  for (const char* name :
       {"corner-error-vs-radius.png", "depth-error-vs-distance.png", "division-residual-vs-radius.png"}) {
    const cv::Mat img = cv::imread((dir_ / "img" / name).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty()) << name;
    EXPECT_EQ(img.cols, 960) << name;
    EXPECT_EQ(img.rows, 600) << name;
    // Drawn on: not a blank page (axes, text and data are dark or coloured).
    cv::Mat grey;
    cv::extractChannel(img, grey, 1);
    EXPECT_GT(cv::countNonZero(grey < 200), 2000) << name;
    EXPECT_NE(report_.find(std::string("](img/") + name + ")"), std::string::npos) << name;
  }
}

}  // namespace
