// `naneye recon --left ... --right ...`: stereo image pairs of any size, as a user with photographs
// from other software runs it (OpenCV's own 640 x 480 stereo chessboard set from opencv-doc).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "run_cli.hpp"

namespace {

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

// A rig for OpenCV's sample camera: its left intrinsics (left_intrinsics.yml: fx 535.9 px) for both
// eyes and a 50 mm baseline; these tests check the image path, not the rig's accuracy. Another
// size scales the camera matrix with it.
std::string write_calibration(const std::filesystem::path& dir, int width = 640, int height = 480) {
  const double s = width / 640.0;
  std::ostringstream kk;
  kk << "[ " << 535.9157 * s << ", 0., " << 342.2832 * s << ", 0., " << 535.9157 * s << ", " << 235.5708 * s
     << ", 0., 0., 1. ]";
  const std::string k = kk.str();
  const std::string d = "[ -0.26637, -0.038589, 0.0017832, -0.00028122, 0.23839 ]";
  std::ostringstream y;
  y << "%YAML:1.0\n---\nimage_width: " << width << "\nimage_height: " << height << "\n";
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

// One photograph pair, scaled to 160 x 120 with its camera matrix: the detector's full search of a
// 640 x 480 pair takes ~2 s of CPU, and what is tested here is the image path.
TEST(ReconImagesCli, APhotographPairGivesItsResultAndAnUnreadablePairIsSkippedAndNamed) {
  ASSERT_TRUE(std::filesystem::exists(kData + "left01.jpg"))
      << "install opencv-doc (scripts/install-deps.sh)";
  TempDir tmp;
  const std::string calib = write_calibration(tmp.path, 160, 120);
  std::string photo[2];
  for (int i = 0; i < 2; ++i) {
    cv::Mat small;
    cv::resize(cv::imread(kData + (i ? "right01.jpg" : "left01.jpg"), cv::IMREAD_UNCHANGED), small,
               cv::Size(160, 120), 0, 0, cv::INTER_AREA);
    photo[i] = (tmp.path / (i ? "right01.png" : "left01.png")).string();
    cv::imwrite(photo[i], small);
  }
  const std::string broken = (tmp.path / "left99.jpg").string();
  std::ofstream(broken) << "\xff\xd8 a JPEG cut after its first marker";
  const auto r =
      naneye::test::run_cli("recon --json --calib " + calib + " --pattern 6x9 --square-mm 25 --left " +
                                photo[0] + " " + broken + " --right " + photo[1] + " " + photo[1],
                            true);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("pair skipped: " + broken + ": not a readable image"), std::string::npos) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 2u) << r.out;  // the pair and the summary
  EXPECT_EQ(lines[0]["pair"], 0);
  // Found or not, the pair says so: a 9 x 6 board's 54 points, or the reason it was not found.
  if (lines[0]["board_found"])
    EXPECT_EQ(lines[0]["points"].size(), 54u);
  else
    EXPECT_TRUE(lines[0].contains("failure")) << lines[0].dump();
  EXPECT_EQ(lines[1]["summary"]["pairs"], 1);
  EXPECT_EQ(lines[1]["summary"]["skipped"], 1);
  // Nothing readable at all: an error exit.
  const auto none =
      naneye::test::run_cli("recon --calib " + calib + " --left " + broken + " --right " + broken);
  EXPECT_NE(none.exit_code, 0);
}

TEST(ReconImagesCli, QuotedPatternsAreExpandedAndPairedInOrder) {
  TempDir tmp;
  const std::string calib = write_calibration(tmp.path, 64, 48);
  // Three small pairs of another camera size (a grey ramp: no board, found quickly to be absent).
  cv::Mat ramp(48, 64, CV_8U);
  for (int r = 0; r < 48; ++r)
    for (int c = 0; c < 64; ++c) ramp.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(2 * c + r);
  for (const char* side : {"l", "r"})
    for (int i = 0; i < 3; ++i) cv::imwrite((tmp.path / (side + std::to_string(i) + ".png")).string(), ramp);
  const std::string dir = tmp.path.string();
  const auto r = naneye::test::run_cli("recon --json --calib " + calib + " --left '" + dir +
                                       "/l*.png' --right '" + dir + "/r*.png'");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto lines = json_lines(r.out);
  ASSERT_EQ(lines.size(), 4u) << r.out;
  for (int i = 0; i < 3; ++i) EXPECT_EQ(lines[i]["pair"], i);
  EXPECT_EQ(lines[3]["summary"]["pairs"], 3);
  const auto unequal = naneye::test::run_cli(
      "recon --calib " + calib + " --left '" + dir + "/l*.png' --right " + dir + "/r0.png", true);
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
