// Device profiles: the shipped files, and refusals that name the file and key.
#include <gtest/gtest.h>

#include <stdexcept>

#include "naneye/driver/usb_profile.hpp"

using namespace naneye::driver;

namespace {
std::string error_of(const std::string& text) {
  try {
    parse_usb_profile(text, "t.toml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(UsbProfile, ShippedProfilesCarryTheSpecIds) {
  const auto dir = std::filesystem::path(NANEYE_SOURCE_DIR) / "config/devices";
  const auto all = load_usb_profiles(dir);
  ASSERT_EQ(all.size(), 2u);
  const auto nano = find_usb_profile(dir, 0x10f8, 0xc487);
  ASSERT_TRUE(nano);
  EXPECT_EQ(nano->name, "cesys-nanousb2");
  EXPECT_EQ(nano->endpoint, 0x86);
  EXPECT_FALSE(nano->endpoint_confirmed);
  EXPECT_EQ(nano->interface, 0);
  EXPECT_EQ(nano->transfer_count, 8);
  EXPECT_EQ(nano->transfer_size, 131072);
  EXPECT_TRUE(nano->bringup_command.empty());
  EXPECT_TRUE(nano->start_controls.empty());
  const auto efm = find_usb_profile(dir, 0x10f8, 0xc482);
  ASSERT_TRUE(efm);
  EXPECT_EQ(efm->name, "cesys-efm01");
  EXPECT_FALSE(find_usb_profile(dir, 0x1234, 0x5678));
}

TEST(UsbProfile, ParsesControlsAndBringup) {
  const auto p = parse_usb_profile(R"(
name = "x"
[usb]
vid = 0x1234
pid = 0xabcd
endpoint = 0x82
alt_setting = 1
[transfers]
count = 4
size = 16384
[bringup]
command = "load-fpga $NANEYE_USB_BUS"
[[start_controls]]
request = 0xB0
value = 0x0102
data = "de ad be ef"
[[start_controls]]
request_type = 0x41
request = 1
)",
                                   "x.toml");
  EXPECT_EQ(p.vid, 0x1234);
  EXPECT_EQ(p.pid, 0xabcd);
  EXPECT_EQ(p.endpoint, 0x82);
  EXPECT_EQ(p.alt_setting, 1);
  EXPECT_EQ(p.transfer_count, 4);
  EXPECT_EQ(p.bringup_command, "load-fpga $NANEYE_USB_BUS");
  ASSERT_EQ(p.start_controls.size(), 2u);
  EXPECT_EQ(p.start_controls[0].request_type, 0x40);
  EXPECT_EQ(p.start_controls[0].value, 0x0102);
  EXPECT_EQ(p.start_controls[0].data, (std::vector<std::uint8_t>{0xde, 0xad, 0xbe, 0xef}));
  EXPECT_EQ(p.start_controls[1].request_type, 0x41);
}

TEST(UsbProfile, RefusalsNameTheKey) {
  EXPECT_NE(error_of("name = \"x\"\n").find("t.toml: [usb]"), std::string::npos);
  EXPECT_NE(error_of("name=\"x\"\n[usb]\nvid=1\npid=2\nendpoint=0x06\n")
                .find("usb.endpoint: must be in [129, 143]"),
            std::string::npos);
  EXPECT_NE(error_of("name=\"x\"\n[usb]\nvid=1\npid=2\nendpoint=0x86\n[transfers]\nsize=1000\n")
                .find("transfers.size: must be a multiple of 512"),
            std::string::npos);
  EXPECT_NE(
      error_of(
          "name=\"x\"\n[usb]\nvid=1\npid=2\nendpoint=0x86\n[[start_controls]]\nrequest=1\ndata=\"abc\"\n")
          .find("start_controls[0].data"),
      std::string::npos);
  EXPECT_NE(error_of("name = \n").find("t.toml:1"), std::string::npos);
}
