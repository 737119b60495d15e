// `naneye calib info`: the figures the issue asks for, read from the real binary's JSON.
#include <gtest/gtest.h>

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
