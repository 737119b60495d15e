#pragma once
// Shared set-up of the integration tests: a fresh capture, a config file, a running naneyed and
// an httplib client on its port.
// clang-format off
#include <Eigen/Core>  // before httplib.h, whose <resolv.h> defines a `_res` macro Eigen trips on
#include <httplib.h>
// clang-format on
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "capture.hpp"
#include "daemon_process.hpp"

namespace naneye::daemon::test {

inline std::string calib_path() {
  return std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml";
}

class NaneyedTest : public ::testing::Test {
 protected:
  TempDir dir;
  std::unique_ptr<DaemonProcess> daemon;
  std::unique_ptr<httplib::Client> client;
  int port = 0;

  std::filesystem::path capture(int pairs, const char* name = "capture.raw") {
    const auto p = dir.path / name;
    truth = write_capture(p, pairs);
    return p;
  }
  CaptureTruth truth;

  // The calibration file the config names (a test may write its own first).
  std::string calibration = calib_path();

  // Writes a config with `extra` appended and starts naneyed on it with `args`.
  void start(const std::string& extra, std::vector<std::string> args = {}) {
    const auto cfg = dir.path / "naneyed.toml";
    std::ofstream(cfg) << "[calibration]\npath = \"" << calibration
                       << "\"\n[http]\nhost = \"127.0.0.1\"\nport = 0\n"
                       << extra
                       // These tests exercise the service (timing, streaming, endpoints) on captures
                       // without a board; the board path is tested where a test asks for [board].
                       << (extra.find("[board]") == std::string::npos ? "[board]\ndetect = false\n" : "");
    args.insert(args.begin(), {"--config", cfg.string()});
    daemon = std::make_unique<DaemonProcess>(args, dir.path / "naneyed.log");
    const auto p = daemon->wait_port();
    ASSERT_TRUE(p.has_value()) << "naneyed did not start:\n" << daemon->log();
    port = *p;
    client = std::make_unique<httplib::Client>("127.0.0.1", port);
    client->set_read_timeout(10, 0);
  }

  // Serves a lossless replay of `file` (file://...?speed=max, `extra` appended to the config) and
  // waits until its `pairs` pairs are processed and, with `until_ended`, the replay has ended (the
  // latest result then stays, so every endpoint reads the same pair). Returns that status.
  nlohmann::json serve_replay(const std::filesystem::path& file, int pairs, const std::string& extra = "",
                              bool until_ended = false) {
    start("[source]\nuri = \"file://" + file.string() + "?speed=max\"\n" + extra);
    return wait_status([&](const nlohmann::json& s) {
      return s["pairs"]["processed"] == pairs && (!until_ended || s["state"] == "stopped");
    });
  }

  nlohmann::json get_json(const std::string& path, int expected_status = 200) {
    auto res = client->Get(path.c_str());
    EXPECT_TRUE(res) << path;
    if (!res) return {};
    EXPECT_EQ(res->status, expected_status) << path << ": " << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "application/json") << path;
    return nlohmann::json::parse(res->body);
  }

  // Polls /v1/status until pred(status) holds; returns the last status.
  template <typename Pred>
  nlohmann::json wait_status(Pred pred, std::chrono::milliseconds timeout = std::chrono::seconds(15)) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    nlohmann::json s;
    while (std::chrono::steady_clock::now() < until) {
      auto res = client->Get("/v1/status");
      if (res && res->status == 200) {
        s = nlohmann::json::parse(res->body);
        if (pred(s)) return s;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ADD_FAILURE() << "status condition not met; last status: " << s.dump();
    return s;
  }
};

}  // namespace naneye::daemon::test
