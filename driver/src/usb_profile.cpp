#include "naneye/driver/usb_profile.hpp"

#include <spdlog/spdlog.h>

#include <toml++/toml.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include "log.hpp"

namespace naneye::driver {
namespace {

[[noreturn]] void bad(const std::string& origin, const std::string& key, const std::string& why) {
  throw std::runtime_error(origin + ": " + key + ": " + why);
}

// Integers may be written in hex in TOML (0x86), which toml++ reads as int64.
std::int64_t integer(const toml::node_view<const toml::node>& n, const std::string& origin,
                     const std::string& key, std::int64_t lo, std::int64_t hi,
                     std::optional<std::int64_t> fallback = std::nullopt) {
  if (!n) {
    if (fallback) return *fallback;
    bad(origin, key, "missing");
  }
  const auto v = n.value<std::int64_t>();
  if (!v) bad(origin, key, "must be an integer");
  if (*v < lo || *v > hi)
    bad(origin, key, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return *v;
}

std::vector<std::uint8_t> hex_bytes(const std::string& text, const std::string& origin,
                                    const std::string& key) {
  std::vector<std::uint8_t> out;
  std::string digits;
  for (char c : text)
    if (!std::isspace(static_cast<unsigned char>(c))) digits += c;
  if (digits.size() % 2) bad(origin, key, "hex string needs an even number of digits");
  for (std::size_t i = 0; i < digits.size(); i += 2) {
    char* end = nullptr;
    const std::string pair = digits.substr(i, 2);
    const long v = std::strtol(pair.c_str(), &end, 16);
    if (*end) bad(origin, key, "not a hex string");
    out.push_back(static_cast<std::uint8_t>(v));
  }
  return out;
}

}  // namespace

UsbProfile parse_usb_profile(const std::string& toml_text, const std::string& origin) {
  toml::table t;
  try {
    t = toml::parse(toml_text, origin);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << origin << ":" << e.source().begin.line << ": " << e.description();
    throw std::runtime_error(msg.str());
  }
  const toml::node_view<const toml::node> root{static_cast<const toml::node&>(t)};
  UsbProfile p;
  p.name = root["name"].value_or(std::string{});
  if (p.name.empty()) bad(origin, "name", "missing");
  p.label = root["label"].value_or(p.name);
  const auto usb = root["usb"];
  if (!usb.is_table()) bad(origin, "[usb]", "missing table");
  p.vid = static_cast<std::uint16_t>(integer(usb["vid"], origin, "usb.vid", 0, 0xFFFF));
  p.pid = static_cast<std::uint16_t>(integer(usb["pid"], origin, "usb.pid", 0, 0xFFFF));
  p.interface = static_cast<int>(integer(usb["interface"], origin, "usb.interface", 0, 255, 0));
  p.alt_setting = static_cast<int>(integer(usb["alt_setting"], origin, "usb.alt_setting", -1, 255, -1));
  p.endpoint = static_cast<std::uint8_t>(integer(usb["endpoint"], origin, "usb.endpoint", 0x81, 0x8F));
  p.endpoint_confirmed = usb["endpoint_confirmed"].value_or(false);
  const auto tr = root["transfers"];
  p.transfer_count = static_cast<int>(integer(tr["count"], origin, "transfers.count", 1, 64, 8));
  p.transfer_size =
      static_cast<int>(integer(tr["size"], origin, "transfers.size", 512, 16 << 20, 128 * 1024));
  if (p.transfer_size % 512)
    bad(origin, "transfers.size", "must be a multiple of 512 (the bulk packet size)");
  p.bringup_command = root["bringup"]["command"].value_or(std::string{});
  if (const auto* arr = root["start_controls"].as_array()) {
    for (std::size_t i = 0; i < arr->size(); ++i) {
      const std::string key = "start_controls[" + std::to_string(i) + "]";
      const toml::node_view<const toml::node> c{arr->get(i)};
      if (!c.is_table()) bad(origin, key, "must be a table");
      UsbControlTransfer x;
      x.request_type =
          static_cast<std::uint8_t>(integer(c["request_type"], origin, key + ".request_type", 0, 0x7F, 0x40));
      x.request = static_cast<std::uint8_t>(integer(c["request"], origin, key + ".request", 0, 0xFF));
      x.value = static_cast<std::uint16_t>(integer(c["value"], origin, key + ".value", 0, 0xFFFF, 0));
      x.index = static_cast<std::uint16_t>(integer(c["index"], origin, key + ".index", 0, 0xFFFF, 0));
      x.data = hex_bytes(c["data"].value_or(std::string{}), origin, key + ".data");
      x.note = c["note"].value_or(std::string{});
      p.start_controls.push_back(std::move(x));
    }
  } else if (root["start_controls"]) {
    bad(origin, "start_controls", "must be an array of tables ([[start_controls]])");
  }
  return p;
}

UsbProfile load_usb_profile(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_usb_profile(s.str(), file.string());
}

std::filesystem::path default_profile_dir() {
  if (const char* env = std::getenv("NANEYE_DEVICE_PROFILES"); env && *env) return env;
#ifdef NANEYE_INSTALLED_PROFILE_DIR
  if (std::filesystem::is_directory(NANEYE_INSTALLED_PROFILE_DIR)) return NANEYE_INSTALLED_PROFILE_DIR;
#endif
#ifdef NANEYE_SOURCE_PROFILE_DIR
  return NANEYE_SOURCE_PROFILE_DIR;
#else
  return "config/devices";
#endif
}

std::vector<UsbProfile> load_usb_profiles(const std::filesystem::path& dir,
                                          std::vector<std::string>* skipped) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<UsbProfile> out;
  for (const auto& f : files) {
    try {
      out.push_back(load_usb_profile(f));
    } catch (const std::exception& e) {
      log()->warn("skipping device profile: {}", e.what());
      if (skipped) skipped->push_back(e.what());
    }
  }
  return out;
}

std::optional<UsbProfile> find_usb_profile(const std::filesystem::path& dir, std::uint16_t vid,
                                           std::uint16_t pid) {
  for (auto& p : load_usb_profiles(dir))
    if (p.vid == vid && p.pid == pid) return p;
  for (auto& p : builtin_usb_profiles())
    if (p.vid == vid && p.pid == pid) return p;
  return std::nullopt;
}

std::vector<UsbProfile> builtin_usb_profiles() {
  UsbProfile nano;
  nano.name = "cesys-nanousb2";
  nano.label = "CESYS NanoUSB2 (NanEye Stereo readout)";
  nano.vid = 0x10f8;
  nano.pid = 0xc487;
  UsbProfile efm = nano;
  efm.name = "cesys-efm01";
  efm.label = "CESYS EFM-01";
  efm.pid = 0xc482;
  return {nano, efm};
}

}  // namespace naneye::driver
