// The sources both naneyed and the CLI open: every scheme (sim:// included), and a device profile
// that does not parse is skipped, named with its reason, not swallowed.
#include <gtest/gtest.h>

#include <fstream>

#include "../daemon/temp_dir.hpp"
#include "naneye/app/sources.hpp"

using namespace naneye;

TEST(Sources, TheRegistryOpensEveryScheme) {
  const auto registry = app::make_source_registry();
  for (const char* scheme : {"usb", "v4l2", "file", "sim"}) EXPECT_TRUE(registry.has(scheme)) << scheme;
}

TEST(Sources, AMalformedDeviceProfileIsReportedWithItsFileAndReason) {
  daemon::test::TempDir dir;
  std::ofstream(dir.path / "bad.toml") << "name = \"bad\"\n[usb]\nvid = 0x1FFFF\npid = 1\nendpoint = 0x82\n";
  std::ofstream(dir.path / "broken.toml") << "[usb\n";
  std::ofstream(dir.path / "good.toml")
      << "name = \"good\"\n[usb]\nvid = 0x1234\npid = 0x5678\nendpoint = 0x82\n";
  const auto scan = app::attached_boards(dir.path);
  ASSERT_EQ(scan.skipped_profiles.size(), 2u);
  EXPECT_NE(scan.skipped_profiles[0].find((dir.path / "bad.toml").string()), std::string::npos)
      << scan.skipped_profiles[0];
  EXPECT_NE(scan.skipped_profiles[0].find("usb.vid"), std::string::npos) << scan.skipped_profiles[0];
  EXPECT_NE(scan.skipped_profiles[1].find((dir.path / "broken.toml").string()), std::string::npos)
      << scan.skipped_profiles[1];
}

TEST(Sources, TheShippedProfilesAreAllRead) {
  EXPECT_TRUE(app::attached_boards(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/devices")
                  .skipped_profiles.empty());
}
