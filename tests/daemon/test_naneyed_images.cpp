// naneyed and image files: images:// replays a folder of stereo pairs, and OpenCV's imgcodecs (with
// the ~110 libraries it maps: GDAL, GDCM, poppler...; 29 MB of resident memory) is loaded only then
// (driver/src/imdecode_lazy.hpp), never by a daemon that serves a camera or a capture.
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "naneyed_fixture.hpp"

namespace naneye::daemon::test {
namespace {

bool maps_imgcodecs(pid_t pid) {
  std::ifstream maps("/proc/" + std::to_string(pid) + "/maps");
  std::stringstream all;
  all << maps.rdbuf();
  return all.str().find("libopencv_imgcodecs") != std::string::npos;
}

TEST_F(NaneyedTest, ImgcodecsIsLoadedOnlyWhenImagesAreRead) {
  serve_replay(capture(3), 3);
  EXPECT_FALSE(maps_imgcodecs(daemon->pid())) << "a capture replay mapped imgcodecs";
  daemon.reset();

  // Three 250 x 250 pairs as 8-bit PNG, in name order.
  const auto folder = dir.path / "pairs";
  std::filesystem::create_directories(folder);
  for (int k = 0; k < 3; ++k) {
    cv::Mat left(250, 250, CV_8U), right(250, 250, CV_8U);
    cv::randu(left, 0, 256);
    cv::randu(right, 0, 256);
    ASSERT_TRUE(cv::imwrite((folder / ("left_" + std::to_string(k) + ".png")).string(), left));
    ASSERT_TRUE(cv::imwrite((folder / ("right_" + std::to_string(k) + ".png")).string(), right));
  }
  start("[source]\nuri = \"images://" + folder.string() + "\"\n");
  const auto st = wait_status([](const nlohmann::json& s) { return s["pairs"]["processed"] == 3; });
  EXPECT_EQ(st["pairs"]["processed"], 3) << st.dump();
  EXPECT_TRUE(maps_imgcodecs(daemon->pid()));
}

}  // namespace
}  // namespace naneye::daemon::test
