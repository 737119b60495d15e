// Calibrations the daemon must refuse (issue 13): at start, on SIGHUP (keeping the one in use, and
// saying so in /v1/status and /metrics) and through rig_problem() itself.
#include <csignal>

#include "naneye/daemon/rig_check.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneyed_fixture.hpp"

using namespace naneye::daemon::test;

namespace {

// The bundled calibration with one line replaced (`key` starts the line, e.g. "image_width:").
std::string paper_with(const std::string& key, const std::string& line) {
  std::istringstream in(read_file(calib_path()));
  std::string out, l;
  bool replaced = false;
  while (std::getline(in, l)) {
    if (!replaced && l.rfind(key, 0) == 0) {
      l = line;
      replaced = true;
    }
    out += l + "\n";
  }
  EXPECT_TRUE(replaced) << key;
  return out;
}

std::string d1_line(const std::string& k1) {
  return "   data: [ " + k1 + ", 0.303, 0., 0., -0.366 ]";
}

}  // namespace

TEST(RigProblem, ThePaperCalibrationPassesAndEachDefectIsNamed) {
  const auto good = naneye::recon::load_rig(std::filesystem::path(calib_path()));
  EXPECT_EQ(naneye::daemon::rig_problem(good, 250), std::nullopt);
  auto r = good;
  r.left = naneye::recon::CameraModel(good.left.K(), good.left.distortion(), 100000, 250);
  EXPECT_NE(naneye::daemon::rig_problem(r, 250).value_or("").find("does not match the 250x250 sensor"),
            std::string::npos);
  r = good;
  auto d = good.right.distortion();
  d.k1 = 1e300;
  r.right = naneye::recon::CameraModel(good.right.K(), d);
  EXPECT_NE(
      naneye::daemon::rig_problem(r, 250).value_or("").find("right camera: distortion coefficient 1e+300"),
      std::string::npos);
  r = good;
  d.k1 = std::nan("");
  r.left = naneye::recon::CameraModel(good.left.K(), d);
  EXPECT_NE(naneye::daemon::rig_problem(r, 250).value_or("").find("not finite"), std::string::npos);
  r = good;
  Eigen::Matrix3d K = good.left.K();
  K(0, 0) = 5;  // CameraModel itself refuses fx <= 0
  r.left = naneye::recon::CameraModel(K, good.left.distortion());
  EXPECT_NE(naneye::daemon::rig_problem(r, 250).value_or("").find("focal length 5 px"), std::string::npos);
  r = good;
  r.T = Eigen::Vector3d::Zero();
  EXPECT_NE(naneye::daemon::rig_problem(r, 250).value_or("").find("baseline 0 mm"), std::string::npos);
  r = good;
  r.R(0, 0) = 2;
  EXPECT_NE(naneye::daemon::rig_problem(r, 250).value_or("").find("R is not a rotation"), std::string::npos);
  // Every calibration shipped in config/calib passes.
  for (const auto& f :
       std::filesystem::directory_iterator(std::string(NANEYE_SOURCE_DIR) + "/config/calib")) {
    if (f.path().extension() != ".yaml") continue;
    try {
      const auto rig = naneye::recon::load_rig(f.path());
      EXPECT_EQ(naneye::daemon::rig_problem(rig, 250), std::nullopt) << f.path();
    } catch (const std::exception&) {
      // Intrinsics-only files load with their extrinsics partner; not a rig on their own.
    }
  }
}

TEST_F(NaneyedTest, ARefusedReloadKeepsTheCalibrationInUseAndSaysWhy) {
  // An image_width of 100000 aborted the worker (std::bad_alloc building its maps); a size other
  // than the sensor's was logged as "reloaded" and no board was found from then on.
  const auto calib = dir.path / "calib.yaml";
  std::ofstream(calib) << read_file(calib_path());
  const auto file = capture(30);
  const auto cfg = dir.path / "naneyed.toml";
  // At half speed the ring spans 258 ms: a pair dropped here is the reloads', not a loaded machine's.
  std::ofstream(cfg) << "[calibration]\npath = \"" << calib.string()
                     << "\"\n[http]\nhost = \"127.0.0.1\"\nport = 0\n[source]\nuri = \"file://"
                     << file.string() << "?speed=0.5&loop=1\"\n[board]\ndetect = false\n";
  daemon = std::make_unique<DaemonProcess>(std::vector<std::string>{"--config", cfg.string()},
                                           dir.path / "naneyed.log");
  port = daemon->wait_port().value_or(0);
  ASSERT_NE(port, 0) << daemon->log();
  client = std::make_unique<httplib::Client>("127.0.0.1", port);
  auto s = wait_status([](const nlohmann::json& j) { return j["pairs"]["processed"] > 3; });
  EXPECT_TRUE(s["calibration"]["last_reload"].is_null());
  const auto dropped_before = s["counters"]["pairs_dropped"].get<int>();  // the start's are not the reloads'

  struct Case {
    std::string text, reason;
  };
  const std::vector<Case> refused{
      {paper_with("image_width:", "image_width: 100000"), "does not match the 250x250 sensor"},
      {paper_with("   data: [ -0.369", d1_line("1e300")), "distortion coefficient 1e+300"},
      {paper_with("   data: [ -0.369", d1_line(".nan")), ""},  // the loader or the check refuses it
      {"%YAML:1.0\n---\nimage_width: [", ""},                  // not even YAML: the loader's own message
  };
  int failures = 0;
  for (const auto& c : refused) {
    std::ofstream(calib, std::ios::trunc) << c.text;
    const auto before = s["pairs"]["processed"].get<int>();
    daemon->signal(SIGHUP);
    ++failures;
    s = wait_status([&](const nlohmann::json& j) {
      return j["calibration"]["reload_failures"] == failures &&
             j["pairs"]["processed"].get<int>() > before + 3;
    });
    ASSERT_TRUE(daemon->running()) << daemon->log();
    EXPECT_EQ(s["calibration"]["last_reload"]["ok"], false);
    EXPECT_NE(s["calibration"]["last_reload"]["reason"].get<std::string>().find(c.reason), std::string::npos)
        << s["calibration"].dump();
    EXPECT_EQ(s["calibration"]["reloads"], 0);
    EXPECT_EQ(s["state"], "streaming");
  }
  auto m = client->Get("/metrics");
  ASSERT_TRUE(m);
  EXPECT_NE(m->body.find("\nnaneye_calibration_reload_failures_total 4\n"), std::string::npos);
  EXPECT_NE(m->body.find("\nnaneye_calibration_last_reload_ok 0\n"), std::string::npos);

  std::ofstream(calib, std::ios::trunc) << read_file(calib_path());
  daemon->signal(SIGHUP);
  s = wait_status([](const nlohmann::json& j) { return j["calibration"]["reloads"] == 1; });
  EXPECT_EQ(s["calibration"]["last_reload"]["ok"], true);
  EXPECT_EQ(s["calibration"]["last_reload"]["reason"], "applied");
  EXPECT_EQ(s["counters"]["pairs_dropped"], dropped_before);
  m = client->Get("/metrics");
  EXPECT_NE(m->body.find("\nnaneye_calibration_last_reload_ok 1\n"), std::string::npos);
  EXPECT_EQ(daemon->stop(SIGTERM).first, 0) << daemon->log();
}

TEST_F(NaneyedTest, ACalibrationForAnotherSensorSizeIsRefusedAtStart) {
  const auto calib = dir.path / "wide.yaml";
  std::ofstream(calib) << paper_with("image_width:", "image_width: 100000");
  const auto cfg = dir.path / "wide.toml";
  // At half speed the ring spans 258 ms: a pair dropped here is the reloads', not a loaded machine's.
  std::ofstream(cfg) << "[calibration]\npath = \"" << calib.string() << "\"\n";
  DaemonProcess check({"--config", cfg.string(), "--check-config"}, dir.path / "wide.log");
  EXPECT_EQ(check.wait_exit(), 1);
  EXPECT_NE(check.log().find("does not match the 250x250 sensor"), std::string::npos) << check.log();
}
