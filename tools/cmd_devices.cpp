// `naneye devices [--json] [--profiles DIR]`: attached NanEye readout boards (ids from the device
// profiles) and V4L2 capture nodes with their formats, each with the URI that opens it.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "naneye/driver/device_list.hpp"

namespace naneye::tools {
namespace {

nlohmann::json to_json(const std::vector<driver::UsbBoardInfo>& usb,
                       const std::vector<driver::V4l2DeviceInfo>& v4l2) {
  nlohmann::json j;
  j["usb"] = nlohmann::json::array();
  for (const auto& b : usb) {
    char id[10];
    std::snprintf(id, sizeof id, "%04x:%04x", b.vid, b.pid);
    j["usb"].push_back({{"id", id},
                        {"bus", b.bus},
                        {"address", b.address},
                        {"serial", b.serial},
                        {"profile", b.profile},
                        {"label", b.label},
                        {"uri", b.uri},
                        {"note", b.note}});
  }
  j["v4l2"] = nlohmann::json::array();
  for (const auto& d : v4l2) {
    nlohmann::json formats = nlohmann::json::array();
    for (const auto& f : d.formats) {
      nlohmann::json sizes = nlohmann::json::array();
      for (const auto& s : f.sizes)
        sizes.push_back({{"width", s.width}, {"height", s.height}, {"range", s.range}});
      formats.push_back(
          {{"fourcc", f.fourcc}, {"description", f.description}, {"usable", f.usable}, {"sizes", sizes}});
    }
    j["v4l2"].push_back({{"path", d.path},
                         {"name", d.name},
                         {"driver", d.driver},
                         {"capture", d.capture},
                         {"formats", formats},
                         {"note", d.note}});
  }
  return j;
}

void print_device_list_text(const nlohmann::json& j) {
  std::cout << "NanEye readout boards (USB):\n";
  if (j["usb"].empty()) std::cout << "  none\n";
  for (const auto& b : j["usb"]) {
    std::cout << "  " << b["id"].get<std::string>() << "  bus " << b["bus"] << " dev " << b["address"] << "  "
              << b["label"].get<std::string>();
    if (!b["serial"].get<std::string>().empty()) std::cout << "  serial " << b["serial"].get<std::string>();
    std::cout << "\n    " << b["uri"].get<std::string>();
    if (!b["note"].get<std::string>().empty()) std::cout << "  (" << b["note"].get<std::string>() << ")";
    std::cout << "\n";
  }
  std::cout << "V4L2 devices:\n";
  if (j["v4l2"].empty()) std::cout << "  none\n";
  for (const auto& d : j["v4l2"]) {
    std::cout << "  " << d["path"].get<std::string>() << "  " << d["name"].get<std::string>();
    if (!d["note"].get<std::string>().empty()) std::cout << "  (" << d["note"].get<std::string>() << ")";
    if (!d["capture"].get<bool>()) std::cout << "  [not a streaming capture node]";
    std::cout << "\n";
    for (const auto& f : d["formats"]) {
      std::cout << "    " << f["fourcc"].get<std::string>() << (f["usable"].get<bool>() ? " *" : "  ") << " ";
      for (const auto& s : f["sizes"])
        std::cout << " " << (s["range"].get<bool>() ? "<=" : "") << s["width"] << "x" << s["height"];
      std::cout << "  " << f["description"].get<std::string>() << "\n";
    }
  }
  std::cout << "(* = a format v4l2:// reads: Y10, Y16, GREY, SGRBG10)\n";
}

}  // namespace

void add_devices_commands(CLI::App& app) {
  auto* cmd = app.add_subcommand("devices", "List attached NanEye readout boards and V4L2 capture devices");
  auto json = std::make_shared<bool>(false);
  auto dir = std::make_shared<std::string>();
  cmd->add_flag("--json", *json, "Print JSON");
  cmd->add_option("--profiles", *dir, "Device profile directory (default: the installed config/devices)");
  cmd->callback([json, dir] {
    auto profiles =
        driver::load_usb_profiles(dir->empty() ? driver::default_profile_dir() : std::filesystem::path(*dir));
    for (auto& b : driver::builtin_usb_profiles()) {
      const bool known = std::any_of(profiles.begin(), profiles.end(), [&](const driver::UsbProfile& p) {
        return p.vid == b.vid && p.pid == b.pid;
      });
      if (!known) profiles.push_back(b);  // the spec's boards are always looked for
    }
    const nlohmann::json j = to_json(driver::list_usb_boards(profiles), driver::list_v4l2_devices());
    if (*json)
      std::cout << j.dump(2) << "\n";
    else
      print_device_list_text(j);
  });
}

}  // namespace naneye::tools
