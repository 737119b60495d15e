// The fuzzed text parsers: calibration YAML, daemon TOML, device-profile TOML, source URIs and the
// HTTP query parser. Each accepts its documented error type and nothing else: any other exception
// escapes to libFuzzer, which reports it as a crash (an error a user would see as a stack trace).
// clang-format off
#include "http_internal.hpp"  // Eigen before httplib (see the header)
// clang-format on

#include <cstdlib>
#include <string>

#include "fuzz_entries.hpp"
#include "naneye/daemon/settings.hpp"
#include "naneye/driver/image_source.hpp"
#include "naneye/driver/source_uri.hpp"
#include "naneye/driver/usb_profile.hpp"
#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye::fuzz {
namespace {

std::string text_of(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

}  // namespace

int load_calibration(const std::uint8_t* data, std::size_t size) {
  // The text as load_rig hands it over once it has read a file (the reading itself is the
  // filesystem's: tests/camera/test_calibration_io.cpp covers what is ours of it), through the
  // entry that returns its refusal: parse_rig is that and a throw.
  std::vector<recon::CalibrationText> texts(1);  // filled in place: an initializer list is copied
  texts[0].name = "<fuzz>";
  texts[0].text.assign(reinterpret_cast<const char*>(data), size);
  const recon::RigOrRefusal read = recon::try_parse_rig(texts);
  if (read.rig) {
    // A rig that loads must be usable: a finite baseline and image size.
    const recon::StereoRig& rig = *read.rig;
    fuzz_check(std::isfinite(rig.baseline_mm()) && rig.left.width() > 0 && rig.left.height() > 0);
  } else {
    fuzz_check(read.refusal.starts_with("<fuzz>"));
  }
  return 0;
}

int parse_daemon_toml(const std::uint8_t* data, std::size_t size) {
  try {
    const daemon::Settings s = daemon::parse_settings(text_of(data, size), "/nonexistent-fuzz-base");
    fuzz_check(s.http_port >= 0 && s.http_port <= 65535);
  } catch (const daemon::SettingsError& e) {
    fuzz_check(e.what()[0] != '\0');
  }
  return 0;
}

int parse_device_profile(const std::uint8_t* data, std::size_t size) {
  try {
    driver::parse_usb_profile(text_of(data, size), "<fuzz>");
  } catch (const std::runtime_error& e) {  // the documented error of usb_profile.hpp
    fuzz_check(std::string(e.what()).starts_with("<fuzz>"));
  }
  return 0;
}

int parse_source_uri(const std::uint8_t* data, std::size_t size) {
  const std::string text = text_of(data, size);
  try {
    const driver::SourceUri uri = driver::parse_uri(text);
    fuzz_check(!uri.scheme.empty());
    // Every scheme's parser on every URI: each must refuse what is not its own with a SourceError.
    try {
      driver::parse_usb_uri(uri);
    } catch (const driver::SourceError&) {
    }
    try {
      driver::parse_v4l2_uri(uri);
    } catch (const driver::SourceError&) {
    }
    try {
      driver::parse_file_uri(uri);
    } catch (const driver::SourceError&) {
    }
    try {
      const driver::ImagesUri im = driver::parse_images_uri(uri);
      fuzz_check(im.fps >= 0 && (im.dir.empty() != im.pairs.empty()));
    } catch (const driver::SourceError&) {
    }
  } catch (const driver::SourceError&) {
  }
  return 0;
}

int parse_http_query(const std::uint8_t* data, std::size_t size) {
  // httplib's own query splitting and percent-decoding (what a request's target goes through), then
  // the daemon's strict readers as the handlers apply them: every key and value must be UTF-8
  // (reject_bad_encoding), and u, v (depth/at) and last_event_id (events) are numbers.
  httplib::Params params;
  httplib::detail::parse_query_text(text_of(data, size), params);
  for (const auto& [key, value] : params) {
    if (!daemon::http::valid_utf8(key) || !daemon::http::valid_utf8(value)) return 0;
    if (key == "u" || key == "v") {
      const auto x = daemon::http::strict_double(value);
      fuzz_check(!x || std::isfinite(*x));
      // Refused text has no decimal number in it: no space, no sign '+', no hex, nothing after.
      if (x) fuzz_check(value.find_first_of(" \txXpP") == std::string::npos && value[0] != '+');
    } else if (key == "last_event_id") {
      const auto id = daemon::http::strict_int(value, 0, INT64_MAX);
      fuzz_check(!id || (*id >= 0 && std::to_string(*id).size() <= value.size()));
    }
  }
  return 0;
}

}  // namespace naneye::fuzz
