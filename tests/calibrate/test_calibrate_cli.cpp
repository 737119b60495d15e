// `naneye calibrate` run as a user runs it, on the bundled simulated captures of the paper's Dataset 3
// rig (tests/data): the YAML it writes is read back by load_rig, and bad input is refused with nothing
// written.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "../tools/run_cli.hpp"
#include "calib_scene.hpp"

using namespace naneye;

namespace {

class CalibrateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("naneye-calibrate-cli-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string data(const std::string& name) const { return std::string(NANEYE_TEST_DATA_DIR) + "/" + name; }
  std::filesystem::path dir_;
};

}  // namespace

TEST_F(CalibrateCli, WritesACalibrationThatLoadRigReads) {
  const auto out = dir_ / "calib.yaml";
  // Two inputs, a path and a URI: the mono capture's 9 full boards and the Bayer capture's 6.
  const test::CliResult r = test::run_cli(
      "calibrate --input " + data("sim-d3-mono/capture.raw") + " --input 'file://" +
          data("sim-d3-bayer/capture.raw") + "?color=grbg' --pattern 6x8 --square-mm 5.99 -o " + out.string(),
      true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("fx"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("+-"), std::string::npos);
  EXPECT_NE(r.out.find("skipped"), std::string::npos);  // the pairs without a full board are counted
  const recon::StereoRig rig = recon::load_rig(out);
  ASSERT_TRUE(rig.sigmas.M1 && rig.sigmas.D2 && rig.sigmas.om && rig.sigmas.T);
  const auto& truth = test::paper_d3();
  // 15 views of real renders and detections: the truth that rendered them within 3 sigma of the file's
  // every estimate, with plausible sigmas.
  auto within = [](double estimate, double want, double sigma, const char* what) {
    if (sigma > 0)
      EXPECT_LE(std::abs(estimate - want), 3 * sigma) << what << ": " << estimate << " vs " << want;
    else
      EXPECT_EQ(estimate, want) << what;
  };
  const std::pair<const recon::CameraModel*, const recon::CameraModel*> cams[2] = {
      {&rig.left, &truth.left}, {&rig.right, &truth.right}};
  for (int eye = 0; eye < 2; ++eye) {
    const Eigen::Matrix3d& M = eye == 0 ? *rig.sigmas.M1 : *rig.sigmas.M2;
    const auto& [est, want] = cams[eye];
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 3; ++j) within(est->K()(i, j), want->K()(i, j), M(i, j), "K");
    const Eigen::Matrix<double, 5, 1>& D = eye == 0 ? *rig.sigmas.D1 : *rig.sigmas.D2;
    const auto& de = est->distortion();
    const auto& dw = want->distortion();
    within(de.k1, dw.k1, D(0), "k1");
    within(de.k2, dw.k2, D(1), "k2");
    within(de.p1, dw.p1, D(2), "p1");
    within(de.p2, dw.p2, D(3), "p2");
    within(de.k3, dw.k3, D(4), "k3");
    EXPECT_GT(M(0, 0), 0.0);
    EXPECT_LT(M(0, 0), 1.0);
  }
  const Eigen::Vector3d om = recon::rodrigues(rig.R), om_truth = recon::rodrigues(truth.R);
  for (int a = 0; a < 3; ++a) {
    within(om(a), om_truth(a), (*rig.sigmas.om)(a), "om");
    within(rig.T(a), truth.T(a), (*rig.sigmas.T)(a), "T");
  }
  EXPECT_EQ((*rig.sigmas.D1)(2), 0.0);  // p1 fixed without --tangential
}

TEST_F(CalibrateCli, JsonReportAndFixK3) {
  const auto out = dir_ / "calib.yaml";
  const test::CliResult r = test::run_cli(
      "calibrate --json --fix-k3 --input " + data("sim-d3-mono") + " -o " + out.string(), false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["ok"].get<bool>());
  EXPECT_EQ(j["pairs"].get<int>(), 12);
  EXPECT_EQ(j["views_used"].get<int>(), static_cast<int>(j["views"].size()));
  EXPECT_GE(j["views_used"].get<int>(), 9);
  EXPECT_GT(j["rms_px"].get<double>(), 0.0);
  EXPECT_LT(j["rms_px"].get<double>(), 0.2);
  EXPECT_EQ(recon::load_rig(out).left.distortion().k3, 0.0);
}

TEST_F(CalibrateCli, RefusesBadInputAndWritesNothing) {
  const auto out = dir_ / "calib.yaml";
  const test::CliResult missing =
      test::run_cli("calibrate --input " + (dir_ / "nothing.raw").string() + " -o " + out.string(), true);
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.out.find("no such file"), std::string::npos) << missing.out;
  const test::CliResult few = test::run_cli(
      "calibrate --max-pairs 3 --input " + data("sim-d3-mono/capture.raw") + " -o " + out.string(), true);
  EXPECT_NE(few.exit_code, 0);
  EXPECT_NE(few.out.find("at least 3"), std::string::npos) << few.out;
  const test::CliResult none = test::run_cli(
      "calibrate --pattern 4x9 --input " + data("sim-d1-cut/capture.raw") + " -o " + out.string(), true);
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.out.find("no board found"), std::string::npos) << none.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
}

// Also: an output named .xml still holds YAML (its provenance lines are YAML comments; appended to
// XML they would not load).
TEST_F(CalibrateCli, MaxViewsThinsEvenly) {
  const auto out = dir_ / "calib.xml";
  const test::CliResult r = test::run_cli(
      "calibrate --json --max-views 4 --input " + data("sim-d3-mono/capture.raw") + " -o " + out.string(),
      false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["views"].size(), 4u);
  // 9 boards found (pairs 1-5, 7-9, 11), every other one kept: pairs 1, 3, 5, 8.
  std::vector<int> pairs;
  for (const auto& v : j["views"]) pairs.push_back(v["pair"].get<int>());
  EXPECT_EQ(pairs, (std::vector<int>{1, 3, 5, 8}));
  EXPECT_NO_THROW(recon::load_rig(out));
}
