// images://: stereo pairs from image files through the byte-stream path (parser, pairer, pool).
#include <gtest/gtest.h>

#include <chrono>

#include "image_test_files.hpp"
#include "naneye/driver/image_source.hpp"
#include "naneye/driver/source_registry.hpp"

namespace naneye::driver {
namespace {

using namespace std::chrono_literals;

std::vector<std::pair<Frame, Frame>> drain_pairs(FrameSource& s) {
  std::vector<std::pair<Frame, Frame>> out;
  while (PairPtr p = s.next(2s)) out.emplace_back(p->left, p->right);
  return out;
}

std::uint16_t ten_bit(int v8) {
  return static_cast<std::uint16_t>((v8 * 1023 + 127) / 255);
}

TEST(ImageSource, AFolderGivesItsLeftAndRightFilesPairedInNameOrderAndSkipsABadPair) {
  test::TempDir dir("images-folder");
  // Written out of order; the folder also holds files that are not pairs of images.
  dir.image("left_2.png", test::ramp(20));
  dir.image("left_0.png", test::ramp(0));
  dir.image("right_0.png", test::ramp(5));
  dir.bytes("right_1.png", "broken");
  dir.image("left_1.png", test::ramp(10));
  dir.image("right_2.pgm", test::ramp(25));
  dir.bytes("left_notes.txt", "not an image name");
  dir.image("left_3.png", test::ramp(30));  // no right partner
  auto s = make_default_registry().open("images://" + dir.str());
  s->start();
  const auto pairs = drain_pairs(*s);
  ASSERT_EQ(pairs.size(), 2u);
  // Pair 0 is left_0/right_0, pair 1 is left_2/right_2 (left_1/right_1 skipped whole).
  EXPECT_EQ(pairs[0].first.at(0, 0), ten_bit(0));
  EXPECT_EQ(pairs[0].second.at(0, 0), ten_bit(5));
  EXPECT_EQ(pairs[1].first.at(3, 4), ten_bit(27));
  EXPECT_EQ(pairs[1].second.at(100, 100), ten_bit((200 + 25) % 256));
  EXPECT_EQ(pairs[0].first.sensor, Sensor::left);
  EXPECT_EQ(pairs[0].second.sensor, Sensor::right);
  EXPECT_EQ(s->state(), SourceState::finished);
  const SourceCounters c = s->counters();
  EXPECT_EQ(c.pairs, 2u);
  EXPECT_EQ(c.transfer_errors, 1u);  // the unreadable pair
  EXPECT_EQ(c.unpaired + c.pairs_dropped + c.sync_losses + c.corrupt_records, 0u);
  ASSERT_TRUE(s->error());
  EXPECT_NE(s->error()->find("1 of 3 pairs skipped"), std::string::npos) << *s->error();
  EXPECT_NE(s->error()->find("right_1.png"), std::string::npos) << *s->error();
  EXPECT_FALSE(s->info().live);  // fps=0: lossless, as fast as taken
  EXPECT_EQ(s->info().kind, "images");
}

TEST(ImageSource, AnExplicitListLoopsAndKeepsTheTimelineGoing) {
  test::TempDir dir("images-list");
  const std::string l = dir.image("a.png", test::ramp(1)), r = dir.image("b.png", test::ramp(2));
  auto s = make_default_registry().open("images://?left=" + l + "&right=" + r + "&loop=1");
  s->start();
  std::vector<std::int64_t> t;
  for (int i = 0; i < 5; ++i) {
    PairPtr p = s->next(2s);
    ASSERT_TRUE(p);
    EXPECT_EQ(p->left.at(1, 1), ten_bit(3));
    t.push_back(p->left.sensor_ns);
  }
  s->stop();
  // 50 fps timestamps when unpaced (20 ms apart, within the tick rounding), rising across passes.
  for (std::size_t i = 1; i < t.size(); ++i) EXPECT_NEAR(t[i] - t[i - 1], 20'000'000, 100);
}

TEST(ImageSource, ImagesOfAnotherSizeAreRefusedWithTheirSizeAndTheReplayFails) {
  const std::string l = test::opencv_photo("left01.jpg"), r = test::opencv_photo("right01.jpg");
  ASSERT_TRUE(std::filesystem::exists(l)) << l << ": install opencv-doc (scripts/install-deps.sh)";
  auto s = make_default_registry().open("images://?left=" + l + "&right=" + r);
  s->start();
  EXPECT_TRUE(drain_pairs(*s).empty());
  EXPECT_EQ(s->state(), SourceState::failed);
  ASSERT_TRUE(s->error());
  EXPECT_NE(s->error()->find("640 x 480 pixels; a frame is 250 x 250"), std::string::npos) << *s->error();
}

TEST(ImageSource, BadUrisAreRefusedNamingTheParameter) {
  const auto error_of = [](const std::string& uri) -> std::string {
    try {
      parse_images_uri(parse_uri(uri));
    } catch (const SourceError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of("images://?left=a.png").find("1 left= but 0 right="), std::string::npos);
  EXPECT_NE(error_of("images://").find("give a folder"), std::string::npos);
  EXPECT_NE(error_of("images:///d?left=a&right=b").find("not both"), std::string::npos);
  EXPECT_NE(error_of("images:///d?fps=-1").find("'fps'"), std::string::npos);
  EXPECT_NE(error_of("images:///d?fps=0x10").find("'fps'"), std::string::npos);
  EXPECT_NE(error_of("images:///d?bits=12").find("'bits'"), std::string::npos);
  EXPECT_NE(error_of("images:///d?speed=max").find("unknown parameter 'speed'"), std::string::npos);
  const ImagesUri ok = parse_images_uri(parse_uri("images:///d?fps=30&color=grbg&bits=10"));
  EXPECT_EQ(ok.fps, 30);
  EXPECT_EQ(ok.image.color, ColorMode::bayer_grbg);
  EXPECT_EQ(ok.image.bits16, 10);
  EXPECT_FALSE(ok.stream.parser.reference.enabled);  // images carry no reference pixels
  // A folder without pairs fails at start, saying what it found.
  test::TempDir dir("images-empty");
  dir.image("left_0.png", test::ramp(0));
  try {
    make_default_registry().open("images://" + dir.str())->start();
    ADD_FAILURE() << "started";
  } catch (const SourceError& e) {
    EXPECT_NE(std::string(e.what()).find("no stereo pair: 1 left* and 0 right*"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace naneye::driver
