// Source URIs and the registry: what is accepted, and that refusals name the parameter and the
// accepted values.
#include <gtest/gtest.h>

#include "naneye/driver/source_registry.hpp"
#include "naneye/driver/source_uri.hpp"

namespace naneye::driver {
namespace {

// The SourceError message of `f()`, or "" if it did not throw.
template <class F>
std::string source_error_of(F f) {
  try {
    f();
  } catch (const SourceError& e) {
    return e.what();
  }
  return "";
}

TEST(SourceUri, UsbDefaultsAndParameters) {
  const UsbUri d = parse_usb_uri(parse_uri("usb://10f8:c487"));
  EXPECT_EQ(d.vid, 0x10f8);
  EXPECT_EQ(d.pid, 0xc487);
  EXPECT_EQ(d.endpoint, 0x86);
  EXPECT_EQ(d.interface, 0);
  EXPECT_FALSE(d.serial);
  const UsbUri u = parse_usb_uri(parse_uri("USB://10F8:C482?serial=AB%20C1&interface=1&endpoint=0x82"));
  EXPECT_EQ(u.pid, 0xc482);
  EXPECT_EQ(*u.serial, "AB C1");
  EXPECT_EQ(u.interface, 1);
  EXPECT_EQ(u.endpoint, 0x82);
}

TEST(SourceUri, UsbRefusalsNameTheParameter) {
  auto e = source_error_of([] { parse_usb_uri(parse_uri("usb://10f8:c487?endpoint=0x06")); });
  EXPECT_NE(e.find("'endpoint'"), std::string::npos) << e;
  EXPECT_NE(e.find("0x81..0x8f"), std::string::npos) << e;
  e = source_error_of([] { parse_usb_uri(parse_uri("usb://10f8:c487?iface=1")); });
  EXPECT_NE(e.find("unknown parameter 'iface'"), std::string::npos) << e;
  EXPECT_NE(e.find("serial, interface, endpoint"), std::string::npos) << e;
  e = source_error_of([] { parse_usb_uri(parse_uri("usb://10f8")); });
  EXPECT_NE(e.find("VID:PID"), std::string::npos) << e;
  e = source_error_of([] { parse_usb_uri(parse_uri("usb://10f8:c487?interface=-1")); });
  EXPECT_NE(e.find("'interface'"), std::string::npos) << e;
}

TEST(SourceUri, V4l2LayoutsAndFormats) {
  const V4l2Uri v = parse_v4l2_uri(parse_uri("v4l2:///dev/video2?layout=top-bottom&format=SGRBG10"));
  EXPECT_EQ(v.device, "/dev/video2");
  EXPECT_EQ(v.layout, V4l2Layout::top_bottom);
  EXPECT_EQ(v.format, V4l2Format::sgrbg10);
  EXPECT_EQ(v.stream.parser.color, ColorMode::bayer_grbg);  // Bayer format implies Bayer frames
  EXPECT_EQ(parse_v4l2_uri(parse_uri("v4l2:///dev/video0?layout=alternate&format=Y10")).layout,
            V4l2Layout::alternate);
  auto e = source_error_of([] { parse_v4l2_uri(parse_uri("v4l2:///dev/video0?layout=diagonal")); });
  EXPECT_NE(e.find("'layout'"), std::string::npos) << e;
  EXPECT_NE(e.find("side-by-side, top-bottom, alternate"), std::string::npos) << e;
  e = source_error_of([] { parse_v4l2_uri(parse_uri("v4l2:///dev/video0?format=MJPG")); });
  EXPECT_NE(e.find("Y10, Y16, GREY, SGRBG10"), std::string::npos) << e;
}

TEST(SourceUri, FileSpeedsLoopAndPlainPaths) {
  FileUri f = parse_file_uri(parse_uri("/tmp/a b.raw"));
  EXPECT_EQ(f.path, "/tmp/a b.raw");
  EXPECT_EQ(f.speed, FileUri::Speed::realtime);
  f = parse_file_uri(parse_uri("file:///tmp/x.neyd?speed=max&loop=1"));
  EXPECT_EQ(f.path, "/tmp/x.neyd");
  EXPECT_EQ(f.speed, FileUri::Speed::max);
  EXPECT_TRUE(f.loop);
  f = parse_file_uri(
      parse_uri("file:///tmp/x.raw?speed=2.5&chunk=512&tolerance_ms=8&color=grbg&reference=reject"));
  EXPECT_EQ(f.speed, FileUri::Speed::factor);
  EXPECT_DOUBLE_EQ(f.factor, 2.5);
  EXPECT_EQ(f.chunk_bytes, 512u);
  EXPECT_EQ(f.stream.pairer.tolerance_ns, 8'000'000);
  EXPECT_EQ(f.stream.parser.color, ColorMode::bayer_grbg);
  EXPECT_TRUE(f.stream.parser.reference.reject);
  auto e = source_error_of([] { parse_file_uri(parse_uri("file:///x.raw?speed=fast")); });
  EXPECT_NE(e.find("'speed'"), std::string::npos) << e;
  EXPECT_NE(e.find("realtime, max"), std::string::npos) << e;
  e = source_error_of([] { parse_file_uri(parse_uri("file:///x.raw?loop=2")); });
  EXPECT_NE(e.find("'loop'"), std::string::npos) << e;
  e = source_error_of([] { parse_file_uri(parse_uri("file:///x.raw?speed=-1")); });
  EXPECT_NE(e.find("'speed'"), std::string::npos) << e;
  e = source_error_of([] { parse_file_uri(parse_uri("file:///x.raw?tolerance_ms=0")); });
  EXPECT_NE(e.find("'tolerance_ms'"), std::string::npos) << e;
}

TEST(SourceUri, GenericParsingForOtherSchemes) {
  const SourceUri u = parse_uri("sim://scene/checker?fps=44&noise=0.5&fps=50");
  EXPECT_EQ(u.scheme, "sim");
  EXPECT_EQ(u.target, "scene/checker");
  EXPECT_EQ(u.params.size(), 3u);
  EXPECT_EQ(*u.param("fps"), "50");
  EXPECT_EQ(*u.param("noise"), "0.5");
  EXPECT_FALSE(u.param("missing"));
  EXPECT_NE(source_error_of([] { parse_uri("file:///x%4"); }).find("percent"), std::string::npos);
  EXPECT_NE(source_error_of([] { parse_uri(""); }), "");
}

TEST(SourceRegistry, OpensFilesAndRefusesUnknownSchemes) {
  SourceRegistry r = make_default_registry();
  EXPECT_TRUE(r.has("file"));
  auto e = source_error_of([&] { r.open("ftp://host/x.raw"); });
  EXPECT_NE(e.find("'ftp://'"), std::string::npos) << e;
  EXPECT_NE(e.find("file://"), std::string::npos) << e;
  // A known but unregistered scheme still gets its parameters checked first.
  e = source_error_of([&] {
    SourceRegistry empty;
    empty.open("usb://10f8:c487?endpoint=zz");
  });
  EXPECT_NE(e.find("'endpoint'"), std::string::npos) << e;
  bool called = false;
  r.add("sim", [&](const SourceUri& u) -> std::unique_ptr<FrameSource> {
    called = u.target == "x";
    return nullptr;
  });
  r.open("sim://x");
  EXPECT_TRUE(called);
  auto src = r.open("/nonexistent/file.raw");  // made, but opening fails at start()
  ASSERT_TRUE(src);
  EXPECT_THROW(src->start(), SourceError);
  EXPECT_EQ(src->state(), SourceState::failed);
}

}  // namespace
}  // namespace naneye::driver
