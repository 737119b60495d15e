// [sensor] fixed_pattern in the running daemon: the status names the pattern in use, and SIGHUP
// reloads it with the calibration; a file that cannot be used is refused there, naming it, and the
// pattern in use stays (docs/sensor-calibration.md). The replay runs at half speed: its ring then
// spans 258 ms, so a pair dropped here is the reload's, not a loaded machine's pre-emption.
#include <fstream>

#include "naneye/sim/flat_field.hpp"
#include "naneyed_fixture.hpp"

namespace naneye::daemon::test {
namespace {

TEST_F(NaneyedTest, SighupReloadsTheFixedPatternAndARefusedOneKeepsTheOneInUse) {
  const auto pattern = dir.path / "fp.yml.gz";
  recon::save_fixed_pattern(pattern, sim::measure_fixed_pattern(sim::SensorSettings{}, 16, 0.7, 1));
  const auto file = capture(30);
  start("[source]\nuri = \"file://" + file.string() +
        "?speed=0.5&loop=1\"\n[board]\ndetect = true\n[sensor]\nfixed_pattern = \"" + pattern.string() +
        "\"\n");
  auto s = wait_status([](const nlohmann::json& j) { return j["pairs"]["processed"] > 3; });
  const auto dropped_before = s["counters"]["pairs_dropped"].get<int>();  // the start's are not the reloads'
  EXPECT_NE(s["processor"].get<std::string>().find("fixed pattern removed (fp.yml.gz"), std::string::npos)
      << s["processor"];

  std::ofstream(pattern, std::ios::trunc) << "%YAML:1.0\nsomething: else\n";
  daemon->signal(SIGHUP);
  s = wait_status([](const nlohmann::json& j) { return j["calibration"]["reload_failures"] == 1; });
  ASSERT_TRUE(daemon->running()) << daemon->log();
  EXPECT_NE(s["calibration"]["last_reload"]["reason"].get<std::string>().find(
                pattern.string() + ": not a naneye fixed-pattern file"),
            std::string::npos)
      << s["calibration"].dump();
  EXPECT_NE(s["processor"].get<std::string>().find("fixed pattern removed"), std::string::npos);
  const auto before = s["pairs"]["processed"].get<int>();
  s = wait_status([&](const nlohmann::json& j) { return j["pairs"]["processed"].get<int>() > before + 3; });
  EXPECT_EQ(s["state"], "streaming");

  // Another sensor's pattern: its figures, not the first one's, are what the status names.
  sim::SensorSettings other;
  other.dsnu_dn = 3.0;
  recon::save_fixed_pattern(pattern, sim::measure_fixed_pattern(other, 16, 0.7, 2));
  daemon->signal(SIGHUP);
  s = wait_status([](const nlohmann::json& j) { return j["calibration"]["reloads"] == 1; });
  EXPECT_EQ(s["calibration"]["last_reload"]["ok"], true);
  EXPECT_EQ(s["processor"].get<std::string>().find("DSNU 0.5 / 0.5 DN"), std::string::npos) << s["processor"];
  EXPECT_NE(s["processor"].get<std::string>().find("fixed pattern removed (fp.yml.gz: DSNU 3."),
            std::string::npos)
      << s["processor"];
  EXPECT_EQ(s["counters"]["pairs_dropped"], dropped_before);
  EXPECT_EQ(daemon->stop(SIGTERM).first, 0) << daemon->log();
}

}  // namespace
}  // namespace naneye::daemon::test
