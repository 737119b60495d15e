#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "naneye/daemon/settings.hpp"

using namespace naneye::daemon;

namespace {

std::string error_of(const std::string& toml) {
  try {
    parse_settings(toml, "/base");
  } catch (const SettingsError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Settings, DefaultsWhenEmpty) {
  const auto s = parse_settings("", "/base");
  EXPECT_EQ(s.source_uri, "auto");
  EXPECT_EQ(s.http_host, "127.0.0.1");
  EXPECT_EQ(s.http_port, 8080);
  EXPECT_TRUE(s.calibration.empty());
}

TEST(Settings, ReadsEveryKeyAndResolvesPathsAgainstTheFile) {
  const auto s = parse_settings(R"(
[source]
uri = "file:///x.raw?speed=max"
sample_capture = "../data/sample.raw"
[calibration]
path = ["intr.yml", "/abs/extr.yml"]
[http]
host = "0.0.0.0"
port = 9001
threads = 6
[pipeline]
corner_sigma_px = 0.1
max_result_age_ms = 250
stall_timeout_ms = 900
history = 32
sse_max_clients = 2
frame_snapshot_interval_ms = 0
[sensor]
fixed_pattern = "fp.yml.gz"
[log]
level = "debug"
)",
                                "/etc/naneye");
  EXPECT_EQ(s.processor.fixed_pattern, std::filesystem::path("/etc/naneye/fp.yml.gz"));
  EXPECT_EQ(s.source_uri, "file:///x.raw?speed=max");
  EXPECT_EQ(s.sample_capture, std::filesystem::path("/etc/data/sample.raw"));
  ASSERT_EQ(s.calibration.size(), 2u);
  EXPECT_EQ(s.calibration[0], std::filesystem::path("/etc/naneye/intr.yml"));
  EXPECT_EQ(s.calibration[1], std::filesystem::path("/abs/extr.yml"));
  EXPECT_EQ(s.http_host, "0.0.0.0");
  EXPECT_EQ(s.http_port, 9001);
  EXPECT_EQ(s.http_threads, 6);
  EXPECT_DOUBLE_EQ(s.processor.reconstructor.reconstruction.corner_sigma_px, 0.1);
  EXPECT_EQ(s.max_result_age_ms, 250);
  EXPECT_EQ(s.stall_timeout_ms, 900);
  EXPECT_EQ(s.history, 32);
  EXPECT_EQ(s.sse_max_clients, 2);
  EXPECT_EQ(s.frame_snapshot_interval_ms, 0);
  EXPECT_EQ(s.log_level, "debug");
}

TEST(Settings, UnknownKeysAreRefusedByName) {
  EXPECT_NE(error_of("[http]\nprot = 80\n").find("http.prot: unknown key"), std::string::npos);
  EXPECT_NE(error_of("[htp]\nport = 80\n").find("htp: unknown section"), std::string::npos);
  EXPECT_NE(error_of("verbose = true\n").find("verbose: unknown key"), std::string::npos);
  EXPECT_NE(error_of("[pipeline.extra]\nx = 1\n").find("pipeline.extra: unknown key"), std::string::npos);
}

TEST(Settings, BadValuesAreRefusedByName) {
  EXPECT_NE(error_of("[http]\nport = 70000\n").find("http.port: must be in 0..65535, got 70000"),
            std::string::npos);
  EXPECT_NE(error_of("[http]\nport = \"80\"\n").find("http.port: expected an integer, got string"),
            std::string::npos);
  EXPECT_NE(error_of("[pipeline]\ncorner_sigma_px = -1.0\n").find("pipeline.corner_sigma_px: must be in"),
            std::string::npos);
  EXPECT_NE(error_of("[pipeline]\nhistory = 1\n").find("pipeline.history: must be in 4..4096"),
            std::string::npos);
  EXPECT_NE(error_of("[log]\nlevel = \"loud\"\n").find("log.level: expected one of"), std::string::npos);
  EXPECT_NE(error_of("[calibration]\npath = [1]\n").find("calibration.path[0]: expected a string"),
            std::string::npos);
  EXPECT_NE(error_of("[http\n").find("TOML syntax error at line 1"), std::string::npos);
}

TEST(Settings, ListenParsesHostAndPort) {
  std::string host;
  int port = -1;
  parse_listen("127.0.0.1:0", "--listen", host, port);
  EXPECT_EQ(host, "127.0.0.1");
  EXPECT_EQ(port, 0);
  parse_listen("[::1]:8081", "--listen", host, port);
  EXPECT_EQ(host, "::1");
  EXPECT_EQ(port, 8081);
  for (const char* bad : {"localhost", ":80", "host:", "host:99999", "host:8o"}) {
    try {
      parse_listen(bad, "--listen", host, port);
      ADD_FAILURE() << bad << " accepted";
    } catch (const SettingsError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--listen: ", 0), 0u) << e.what();
    }
  }
}

TEST(Settings, ValidateChecksFilesAndThreadBudget) {
  Settings s;
  try {
    validate(s);
    ADD_FAILURE() << "no calibration accepted";
  } catch (const SettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("calibration.path: is required"), std::string::npos);
  }
  s.calibration = {std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"};
  EXPECT_NO_THROW(validate(s));
  s.calibration = {"/nonexistent/calib.yaml"};
  EXPECT_THROW(validate(s), SettingsError);
  s.calibration = {std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"};
  s.sse_max_clients = s.http_threads;
  try {
    validate(s);
    ADD_FAILURE() << "sse_max_clients >= http.threads accepted";
  } catch (const SettingsError& e) {
    EXPECT_NE(std::string(e.what()).find("pipeline.sse_max_clients"), std::string::npos);
  }
}

TEST(Settings, TheShippedConfigIsValid) {
  const auto s = load_settings(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/naneyed.toml");
  EXPECT_EQ(s.source_uri, "auto");
  ASSERT_EQ(s.calibration.size(), 1u);
  EXPECT_TRUE(std::filesystem::is_regular_file(s.calibration[0])) << s.calibration[0];
}

TEST(Settings, ReconModeIsReadAndValidatedByName) {
  EXPECT_EQ(parse_settings("", "/base").processor.mode, ReconMode::board);  // until scene fits 62 fps
  EXPECT_EQ(parse_settings("[recon]\nmode = \"board\"\n", "/base").processor.mode, ReconMode::board);
  EXPECT_EQ(parse_settings("[recon]\nmode = \"scene\"\n", "/base").processor.mode, ReconMode::scene);
  EXPECT_EQ(parse_settings("[recon]\nmode = \"both\"\n", "/base").processor.mode, ReconMode::both);
  EXPECT_NE(error_of("[recon]\nmode = \"dense\"\n").find("recon.mode: expected one of board, scene, both"),
            std::string::npos);
  EXPECT_NE(error_of("[recon]\nmode = 1\n").find("recon.mode: expected a string"), std::string::npos);
  EXPECT_NE(error_of("[recon]\nmodes = \"board\"\n").find("recon.modes: unknown key"), std::string::npos);
  // threads: the dense map on a second thread (2, the default) or on the worker's own (1).
  EXPECT_EQ(parse_settings("", "/base").processor.threads, 2);
  EXPECT_EQ(parse_settings("[recon]\nthreads = 1\n", "/base").processor.threads, 1);
  EXPECT_NE(error_of("[recon]\nthreads = 3\n").find("recon.threads:"), std::string::npos);
  EXPECT_NE(error_of("[recon]\nthreads = 0\n").find("recon.threads:"), std::string::npos);
}

TEST(Settings, TheBoardKeysLandInTheReconStructs) {
  const auto defaults = parse_settings("", "/base").processor;
  const naneye::recon::BoardGeometry paper;  // the one place the paper's board is stated
  EXPECT_EQ(defaults.reconstructor.corners.board.rows, paper.rows);
  EXPECT_EQ(defaults.reconstructor.corners.board.cols, paper.cols);
  EXPECT_DOUBLE_EQ(defaults.reconstructor.corners.board.square_mm, paper.square_mm);
  EXPECT_TRUE(defaults.reconstructor.tracking);
  EXPECT_TRUE(defaults.detect);
  const auto s = parse_settings(
      "[board]\nrows = 5\ncols = 7\nsquare_mm = 3.5\ntracking = false\ndetect = false\n"
      "[pipeline]\ncorner_sigma_px = 0.2\n",
      "/base");
  const auto& r = s.processor.reconstructor;
  EXPECT_EQ(r.corners.board.rows, 5);
  EXPECT_EQ(r.corners.board.cols, 7);
  EXPECT_DOUBLE_EQ(r.corners.board.square_mm, 3.5);
  EXPECT_DOUBLE_EQ(r.reconstruction.corner_sigma_px, 0.2);
  EXPECT_FALSE(r.tracking);
  EXPECT_FALSE(s.processor.detect);
  EXPECT_NE(error_of("[board]\nrows = 9\n").find("board.rows: must be in 2..8"), std::string::npos);
}

TEST(Settings, CheckNamesTheKeyAndRunsTheProcessorsCheck) {
  Settings s;
  s.calibration = {std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"};
  EXPECT_EQ(s.check(), "");
  s.http_host.clear();
  EXPECT_EQ(s.check(), "http.host: must not be empty");
  s.http_host = "127.0.0.1";
  s.processor.reconstructor.corners.board.square_mm = -1;
  EXPECT_EQ(s.check().rfind("board.square_mm: ", 0), 0u) << s.check();
  EXPECT_THROW(validate(s), SettingsError);
}
