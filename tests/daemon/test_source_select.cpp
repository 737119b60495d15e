// "auto" and what it says: the board found or the sample capture, and any device profile the scan
// skipped (the reason is what /v1/status shows as source.reason).
#include <gtest/gtest.h>

#include "naneye/daemon/source_select.hpp"

using namespace naneye;

namespace {

daemon::BoardLister lister(std::vector<std::string> uris, std::vector<std::string> skipped) {
  return [=] { return app::BoardScan{uris, skipped}; };
}

}  // namespace

TEST(SourceSelect, AConfiguredUriIsTakenAsGiven) {
  daemon::Settings s;
  s.source_uri = "sim://?preset=paper-d3";
  const auto c = daemon::choose_source(s, lister({"usb://x"}, {}));
  EXPECT_EQ(c.uri, "sim://?preset=paper-d3");
  EXPECT_EQ(c.reason, "configured");
  EXPECT_FALSE(c.fallback);
}

TEST(SourceSelect, AutoTakesTheFirstBoardOrTheSampleCapture) {
  daemon::Settings s;
  s.sample_capture = "/data/sample.raw";
  auto c = daemon::choose_source(s, lister({"usb://a", "usb://b"}, {}));
  EXPECT_EQ(c.uri, "usb://a");
  EXPECT_EQ(c.reason, "auto: first attached NanEye readout board (2 attached)");
  c = daemon::choose_source(s, lister({}, {}));
  EXPECT_EQ(c.uri, "file:///data/sample.raw?speed=realtime&loop=1");
  EXPECT_TRUE(c.fallback);
  EXPECT_EQ(c.reason.find("skipped"), std::string::npos);
}

TEST(SourceSelect, SkippedDeviceProfilesAreSaidInTheReason) {
  daemon::Settings s;
  s.sample_capture = "/data/sample.raw";
  const std::string why = "/etc/naneye/devices/mine.toml: usb.vid: must be an integer";
  auto c = daemon::choose_source(s, lister({}, {why}));
  EXPECT_TRUE(c.fallback);
  EXPECT_NE(c.reason.find("device profiles skipped: " + why), std::string::npos) << c.reason;
  c = daemon::choose_source(s, lister({"usb://a"}, {why, "b.toml: x"}));
  EXPECT_NE(c.reason.find(why + "; b.toml: x"), std::string::npos) << c.reason;
  s.sample_capture.clear();
  try {
    daemon::choose_source(s, lister({}, {why}));
    ADD_FAILURE() << "no board and no sample capture accepted";
  } catch (const daemon::SettingsError& e) {
    EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
  }
}
