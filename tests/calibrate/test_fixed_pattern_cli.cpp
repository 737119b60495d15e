// `naneye fixed-pattern` run as a user runs it: capped and flat frames of the measured sensor
// (sim::SensorSettings::measured, written as 16-bit PNG pairs and read back through images://) give
// a file whose maps hold the die's DSNU and PRNU; `naneye recon --fixed-pattern` reads it; frames
// that saw light, too few frames and a missing flat level are refused with nothing written, and a
// write that fails leaves no half file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "../tools/run_cli.hpp"
#include "naneye/recon/camera/fixed_pattern_io.hpp"
#include "naneye/sim/flat_field.hpp"

namespace naneye::fixed_pattern_cli_test {
namespace {

class FixedPatternCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        std::filesystem::temp_directory_path() / ("naneye-fixed-pattern-cli-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // `frames` pairs at `level` of white into DIR/left-NNN.png, DIR/right-NNN.png (10-bit values).
  std::string write_frames(const std::string& name, double level, int frames) {
    const auto d = dir_ / name;
    std::filesystem::create_directories(d);
    const sim::SensorModel model(sim::SensorSettings::measured(false));
    sim::Rng rng(static_cast<std::uint64_t>(level * 1000) + 1);
    sim::SensorModel::Scratch scratch;
    cv::Mat frame;
    for (int i = 0; i < frames; ++i)
      for (int eye = 0; eye < 2; ++eye) {
        sim::expose_calibration_frame(model, eye, level, rng, scratch, frame);
        char file[32];
        std::snprintf(file, sizeof file, "%s-%03d.png", eye == 0 ? "left" : "right", i);
        cv::imwrite((d / file).string(), frame);
      }
    return "'images://" + d.string() + "?bits=10'";
  }
  std::filesystem::path dir_;
};

TEST_F(FixedPatternCli, WritesTheDiesPatternAndReconReadsIt) {
  const std::string dark = write_frames("dark", 0.0, 32), flat = write_frames("flat", 0.7, 32);
  const auto out = dir_ / "fp.yml.gz";
  const test::CliResult r = test::run_cli(
      "fixed-pattern --dark " + dark + " --flat " + flat + " --frames 32 -o " + out.string(), true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("PRNU"), std::string::npos) << r.out;
  const recon::StereoFixedPattern p = recon::load_fixed_pattern(out);
  // The measured die: DSNU 3.8 DN with column FPN 0.55 DN (3.84 together), PRNU 2 %.
  for (const recon::FixedPattern* eye : {&p.left, &p.right}) {
    EXPECT_EQ(eye->dark_frames, 32);
    EXPECT_EQ(eye->flat_frames, 32);
    EXPECT_NEAR(eye->dsnu_dn, 3.84, 0.2);
    EXPECT_NEAR(eye->prnu, 0.02, 0.003);
    EXPECT_NEAR(eye->dark_se_dn, 2.5 / std::sqrt(32.0), 0.05);  // read noise 2.5 DN over 32 frames
  }
  // The file read by recon on a capture: the board path runs on the corrected frames.
  const test::CliResult rec =
      test::run_cli("recon --calib " + std::string(NANEYE_SOURCE_DIR) +
                        "/config/calib/paper-d3.yaml --input " + std::string(NANEYE_TEST_DATA_DIR) +
                        "/sim-d3-mono/capture.raw --max-pairs 2 --json " + "--fixed-pattern " + out.string(),
                    false);
  EXPECT_EQ(rec.exit_code, 0) << rec.out;
  EXPECT_NE(rec.out.find("\"pair\""), std::string::npos) << rec.out;
}

TEST_F(FixedPatternCli, RefusesWithNothingWritten) {
  const auto out = dir_ / "fp.yml";
  const std::string dark = write_frames("dark", 0.0, 16);
  // "Dark" frames of a lit scene: the flat frames given as dark.
  const std::string lit = write_frames("lit", 0.7, 16);
  test::CliResult r = test::run_cli("fixed-pattern --dark " + lit + " --frames 16 -o " + out.string(), true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("saw light"), std::string::npos) << r.out;
  // Fewer frames than the maps need.
  r = test::run_cli("fixed-pattern --dark " + dark + " --frames 8 -o " + out.string(), true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("--frames: Value 8 not in range 16 to 100000"), std::string::npos) << r.out;
  // Fewer pairs in the source than --frames asks for.
  r = test::run_cli("fixed-pattern --dark " + dark + " --frames 40 -o " + out.string(), true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("ended after 16 pairs"), std::string::npos) << r.out;
  // A flat too dim to read gains off.
  const std::string dim = write_frames("dim", 0.05, 16);
  r = test::run_cli("fixed-pattern --dark " + dark + " --flat " + dim + " --frames 16 -o " + out.string(),
                    true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("more light"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
  // Offsets only is a pattern.
  r = test::run_cli("fixed-pattern --dark " + dark + " --frames 16 -o " + out.string(), true);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(recon::load_fixed_pattern(out).left.gain.empty());
}

// The file is written beside its target and renamed over it (tools/replace_file.cpp): when the
// rename fails (the target a directory that holds a file), the target stays as it was and no
// temporary is left.
TEST_F(FixedPatternCli, AFailedReplaceLeavesTheTargetAndNoTemporary) {
  const auto out = dir_ / "fp.yml";
  std::filesystem::create_directories(out);
  std::FILE* keep = std::fopen((out / "keep").c_str(), "w");
  ASSERT_NE(keep, nullptr);
  std::fclose(keep);
  const std::string dark = write_frames("dark", 0.0, 16);
  const test::CliResult r =
      test::run_cli("fixed-pattern --dark " + dark + " --frames 16 -o " + out.string(), true);
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("cannot rename"), std::string::npos) << r.out;  // the rename, not an earlier step
  EXPECT_TRUE(std::filesystem::is_directory(out));
  EXPECT_TRUE(std::filesystem::exists(out / "keep"));
  for (const auto& e : std::filesystem::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().rfind(".part-", 0), std::string::npos) << e.path();
}

}  // namespace
}  // namespace naneye::fixed_pattern_cli_test
