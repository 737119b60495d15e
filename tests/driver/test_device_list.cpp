// `naneye devices` listings against emulated hardware.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include "naneye/driver/device_list.hpp"
#include "usb_emulator.hpp"
#include "v4l2_emulator.hpp"

using namespace naneye::driver;

TEST(DeviceList, FindsTheBoardByItsProfileIds) {
  naneye::test::UsbEmulator emu;
  naneye::test::UsbDeviceSpec spec;
  spec.pid = 0xc482;  // EFM-01
  spec.bus = 2;
  spec.address = 9;
  spec.serial = "EFM42";
  emu.plug(spec, {});
  const auto boards = list_usb_boards(builtin_usb_profiles());
  ASSERT_EQ(boards.size(), 1u);
  EXPECT_EQ(boards[0].vid, 0x10f8);
  EXPECT_EQ(boards[0].pid, 0xc482);
  EXPECT_EQ(boards[0].bus, 2);
  EXPECT_EQ(boards[0].address, 9);
  EXPECT_EQ(boards[0].serial, "EFM42");
  EXPECT_EQ(boards[0].profile, "cesys-efm01");
  EXPECT_EQ(boards[0].uri, "usb://10f8:c482?serial=EFM42");
  EXPECT_TRUE(boards[0].note.empty()) << boards[0].note;

  auto only_nanousb2 = builtin_usb_profiles();
  only_nanousb2.resize(1);
  EXPECT_TRUE(list_usb_boards(only_nanousb2).empty());
}

TEST(DeviceList, ListsV4l2FormatsAndSizes) {
  naneye::test::V4l2Emulator emu;
  naneye::test::V4l2DeviceSpec spec;
  spec.index = 2;
  spec.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Y10};
  emu.plug(spec, {});
  const auto devs = list_v4l2_devices();
  ASSERT_EQ(devs.size(), 1u);
  EXPECT_EQ(devs[0].path, "/dev/video2");
  EXPECT_EQ(devs[0].name, spec.card);
  EXPECT_TRUE(devs[0].capture);
  ASSERT_EQ(devs[0].formats.size(), 2u);
  EXPECT_EQ(devs[0].formats[0].fourcc, "YUYV");
  EXPECT_FALSE(devs[0].formats[0].usable);
  EXPECT_EQ(devs[0].formats[1].fourcc, "Y10 ");
  EXPECT_TRUE(devs[0].formats[1].usable);
  ASSERT_EQ(devs[0].formats[1].sizes.size(), 1u);
  EXPECT_EQ(devs[0].formats[1].sizes[0].width, 500u);
  EXPECT_EQ(devs[0].formats[1].sizes[0].height, 250u);
}
