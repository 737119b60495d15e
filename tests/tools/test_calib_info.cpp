// `naneye calib info`: the figures the issue asks for, read from the real binary's JSON.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "run_cli.hpp"

using naneye::test::run_cli;

TEST(CalibInfo, Dataset3Json) {
  const auto r =
      run_cli(std::string("calib info --json ") + NANEYE_SOURCE_DIR + "/config/calib/paper-d3.yaml");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["left"]["fold_radius_px"].get<double>(), 138.6, 0.05);
  EXPECT_TRUE(j["right"]["fold_radius_px"].is_null());
  EXPECT_NEAR(j["left"]["valid_pixel_share"].get<double>(), 0.883, 0.001);
  EXPECT_DOUBLE_EQ(j["right"]["valid_pixel_share"].get<double>(), 1.0);
  EXPECT_LE(j["left"]["max_roundtrip_error_px"].get<double>(), 1e-6);
  EXPECT_LE(j["right"]["max_roundtrip_error_px"].get<double>(), 1e-6);
  EXPECT_NEAR(j["rig"]["baseline_mm"].get<double>(), 1.0886, 1e-4);
  EXPECT_NEAR(j["rig"]["rotation_deg"].get<double>(), 2.108, 1e-3);
  EXPECT_DOUBLE_EQ(j["left"]["D"][0].get<double>(), -0.369);
  // The paper gives marginal sigmas only: no depth sigma to stand behind, the independent what-if
  // beside it (all four depths seen by the right eye on this rig).
  EXPECT_TRUE(j["calibration_depth_sigma"].is_null());
  const auto& what_if = j["calibration_depth_sigma_if_independent"]["on_axis"];
  ASSERT_EQ(what_if.size(), 4u);
  EXPECT_NEAR(what_if[0]["z_mm"].get<double>(), 10 * 1.0886, 1e-3);
  for (std::size_t i = 1; i < what_if.size(); ++i)
    EXPECT_GT(what_if[i]["sigma_mm"].get<double>(), what_if[i - 1]["sigma_mm"].get<double>());
}

TEST(CalibInfo, BadFileIsAClearError) {
  const auto r = run_cli("calib info /nonexistent/calib.yaml", true);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.out.find("calib.yaml"), std::string::npos) << r.out;
}

TEST(CalibInfo, MissingKeyNamesFileAndKey) {
  const std::string path = ::testing::TempDir() + "/naneye-partial.yaml";
  FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_TRUE(f);
  std::fputs("%YAML:1.0\n---\nimage_width: 250\nimage_height: 250\n", f);
  std::fclose(f);
  const auto r = run_cli("calib info " + path, true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("naneye-partial.yaml: key 'M1': missing"), std::string::npos) << r.out;
}

namespace {

// The bundled calibration with the right camera's k1 replaced, written to a temporary file.
std::string paper_with_right_k1(const std::string& k1, const char* name) {
  std::ifstream in(std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto d2 = text.find("D2:");
  const auto data = text.find("data: [", d2);
  const auto comma = text.find(',', data);
  text.replace(data + 7, comma - data - 7, " " + k1);
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(CalibInfo, RefusesWhatTheDaemonRefuses) {
  // A distortion of 1e300 was described as if it were a camera (exit 0, a fold radius, a share).
  const auto bad = paper_with_right_k1("1e300", "naneye-k1-1e300.yaml");
  const auto r = run_cli("calib info " + bad, true);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("naneye-k1-1e300.yaml: not a usable calibration: right camera: distortion "
                       "coefficient 1e+300 beyond +-100"),
            std::string::npos)
      << r.out;
}

TEST(CalibExport, RefusesWhatTheDaemonRefuses) {
  const auto bad = paper_with_right_k1("1e300", "naneye-export-1e300.yaml");
  const std::string out = ::testing::TempDir() + "/naneye-export-refused";
  const auto r = run_cli("calib export --format ros --out " + out + " " + bad, true);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("not a usable calibration: right camera: distortion coefficient 1e+300"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(out + "/left.yaml")) << "nothing is written for it";
}
