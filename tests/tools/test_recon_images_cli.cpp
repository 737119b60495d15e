// `naneye recon --left ... --right ...`: stereo image pairs of any size, as a user with photographs
// from other software runs it (OpenCV's own 640 x 480 stereo chessboard set from opencv-doc).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "run_cli.hpp"

namespace {

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

// A rig for OpenCV's sample camera: its left intrinsics (left_intrinsics.yml: fx 535.9 px) for both
// eyes and a 50 mm baseline; these tests check the image path, not the rig's accuracy.
std::string write_calibration(const std::filesystem::path& dir) {
  const std::string k = "[ 535.9157, 0., 342.2832, 0., 535.9157, 235.5708, 0., 0., 1. ]";
  const std::string d = "[ -0.26637, -0.038589, 0.0017832, -0.00028122, 0.23839 ]";
  std::ostringstream y;
  y << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  for (const char* m : {"M1", "M2"})
    y << m << ": !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: " << k << "\n";
  for (const char* m : {"D1", "D2"})
    y << m << ": !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: " << d << "\n";
  y << "R: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   data: [ 1., 0., 0., 0., 1., 0., 0., 0., 1. "
       "]\n";
  y << "T: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ -50., 0., 0. ]\n";
  const auto path = dir / "opencv-sample.yaml";
  std::ofstream(path) << y.str();
  return path.string();
}

struct TempDir {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("naneye-recon-images-" + std::to_string(::getpid()));
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() { std::filesystem::remove_all(path); }
};

std::vector<nlohmann::json> json_lines(const std::string& out) {
  std::vector<nlohmann::json> v;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] == '{') v.push_back(nlohmann::json::parse(line));
  return v;
}

TEST(ReconImagesCli, PhotographsGiveOneResultPerPairAndAnUnreadablePairIsSkippedAndNamed) {
  ASSERT_TRUE(std::filesystem::exists(kData + "left01.jpg"))
      << "install opencv-doc (scripts/install-deps.sh)";
  TempDir tmp;
  const std::string calib = write_calibration(tmp.path);
  const std::string broken = (tmp.path / "left99.jpg").string();
  std::ofstream(broken) << "\xff\xd8 a JPEG cut after its first marker";
  const auto r =
      naneye::test::run_cli("recon --json --calib " + calib + " --pattern 6x9 --square-mm 25 --left " +
                            kData + "left01.jpg " + kData + "left02.jpg " + broken + " --right " + kData +
                            "right01.jpg " + kData + "right02.jpg " + kData + "right03.jpg");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;  // two pairs and the summary
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(lines[i]["pair"], i);
    // Found or not, the pair says so: a 9 x 6 board's 54 points, or the reason it was not found.
    if (lines[i]["board_found"])
      EXPECT_EQ(lines[i]["points"].size(), 54u);
    else
      EXPECT_TRUE(lines[i].contains("failure")) << lines[i].dump();
  }
  EXPECT_EQ(lines[2]["summary"]["pairs"], 2);
  EXPECT_EQ(lines[2]["summary"]["skipped"], 1);
  const auto err = naneye::test::run_cli(
      "recon --calib " + calib + " --pattern 6x9 --left " + broken + " --right " + kData + "right03.jpg",
      true);
  EXPECT_NE(err.exit_code, 0);
  EXPECT_NE(err.out.find("pair skipped: " + broken + ": not a readable image"), std::string::npos) << err.out;
}

TEST(ReconImagesCli, QuotedPatternsAreExpandedSortedAndPairedInOrder) {
  ASSERT_TRUE(std::filesystem::exists(kData + "left01.jpg"))
      << "install opencv-doc (scripts/install-deps.sh)";
  TempDir tmp;
  const std::string calib = write_calibration(tmp.path);
  const auto r =
      naneye::test::run_cli("recon --json --calib " + calib + " --pattern 6x9 --square-mm 25 --left '" +
                            kData + "left0[1-3].jpg' --right '" + kData + "right0[1-3].jpg'");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 4u) << r.out;
  EXPECT_EQ(lines[3]["summary"]["pairs"], 3);
  const auto unequal = naneye::test::run_cli(
      "recon --calib " + calib + " --left '" + kData + "left0[1-3].jpg' --right " + kData + "right01.jpg",
      true);
  EXPECT_NE(unequal.exit_code, 0);
  EXPECT_NE(unequal.out.find("--left names 3 files and --right 1"), std::string::npos) << unequal.out;
}

TEST(ReconImagesCli, ImagesOfAnotherSizeThanTheCalibrationAreRefusedWithBothSizes) {
  ASSERT_TRUE(std::filesystem::exists(kData + "left01.jpg"))
      << "install opencv-doc (scripts/install-deps.sh)";
  const auto r = naneye::test::run_cli("recon --calib " + std::string(NANEYE_SOURCE_DIR) +
                                           "/config/calib/paper-d3.yaml --left " + kData +
                                           "left01.jpg --right " + kData + "right01.jpg",
                                       true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("640 x 480 pixels, but the calibration is for 250 x 250"), std::string::npos) << r.out;
}

}  // namespace
