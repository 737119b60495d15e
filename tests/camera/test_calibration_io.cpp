// Calibration files: OpenCV stereo_calib keys, split or whole, sigmas, what OpenCV's FileStorage
// writes (read with yaml-cpp), and refusals that name the file, the key and the problem.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <string>
#include <vector>

#include "naneye/recon/camera/calibration_io.hpp"

namespace fs = std::filesystem;
using naneye::recon::CalibrationError;
using naneye::recon::load_rig;

namespace {

const fs::path kDefault = fs::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml";

class CalibFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("naneye-calib-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    std::ifstream in(kDefault);
    text_.assign(std::istreambuf_iterator<char>(in), {});
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& content) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << content;
    return p;
  }
  // The default file with the first occurrence of `from` replaced by `to` (plain text, no regex:
  // GCC 12's std::regex trips -Wmaybe-uninitialized under ASan).
  fs::path variant(const std::string& from, const std::string& to) {
    std::string out = text_;
    const auto at = out.find(from);
    EXPECT_NE(at, std::string::npos) << "not in the default file: " << from;
    if (at != std::string::npos) out.replace(at, from.size(), to);
    return write("variant.yaml", out);
  }
  // Expects load_rig to throw with a message containing every fragment.
  void expect_refused(const fs::path& file, std::initializer_list<std::string> fragments) {
    try {
      load_rig(file);
      ADD_FAILURE() << "accepted " << file;
    } catch (const CalibrationError& e) {
      const std::string msg = e.what();
      for (const auto& f : fragments)
        EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
  }

  fs::path dir_;
  std::string text_;
};

}  // namespace

TEST_F(CalibFiles, DefaultIsThePapersDataset3) {
  const auto rig = load_rig(kDefault);
  EXPECT_DOUBLE_EQ(rig.left.fx(), 216.360);
  EXPECT_DOUBLE_EQ(rig.left.cy(), 111.535);
  EXPECT_DOUBLE_EQ(rig.left.distortion().k3, -0.366);
  EXPECT_DOUBLE_EQ(rig.right.distortion().k3, 0.866);
  // The paper's relative pose: omega = (-0.0034, 0.0134, 0.0341), right origin C = (1.063, -0.203, 0.118).
  const Eigen::Vector3d om = naneye::recon::rodrigues(rig.R);
  EXPECT_NEAR((om - Eigen::Vector3d(-0.0034, 0.0134, 0.0341)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((rig.right_center() - Eigen::Vector3d(1.063, -0.203, 0.118)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(rig.rotation_angle_rad() * 180 / M_PI, 2.1, 0.02);  // "approximately 2.1 degrees"
  ASSERT_TRUE(rig.sigmas.M1);
  EXPECT_DOUBLE_EQ((*rig.sigmas.M1)(0, 0), 0.579);
  ASSERT_TRUE(rig.sigmas.D2);
  EXPECT_DOUBLE_EQ((*rig.sigmas.D2)(4), 0.499);
  EXPECT_FALSE(rig.sigmas.om);
}

TEST_F(CalibFiles, SaveLoadRoundTripIsExact) {
  const auto rig = load_rig(kDefault);
  const fs::path out = dir_ / "saved.yaml";
  naneye::recon::save_rig(rig, out);
  const auto back = load_rig(out);
  EXPECT_EQ(back.left.K(), rig.left.K());
  EXPECT_EQ(back.right.K(), rig.right.K());
  EXPECT_EQ(back.R, rig.R);
  EXPECT_EQ(back.T, rig.T);
  EXPECT_EQ(back.left.distortion().k2, rig.left.distortion().k2);
  EXPECT_EQ(*back.sigmas.T, *rig.sigmas.T);
  EXPECT_EQ(*back.sigmas.D1, *rig.sigmas.D1);
}

// The full covariance naneye's calibration writes (rig.hpp's order) reads back to the bit, and a
// matrix that cannot be a covariance (asymmetric, a negative direction) is refused by name: a
// point's calibration sigma is a quadratic form in it.
TEST_F(CalibFiles, CovarianceRoundTripsAndMustBeACovariance) {
  auto rig = load_rig(kDefault);
  EXPECT_FALSE(rig.sigmas.covariance);  // the paper gives marginal sigmas only
  Eigen::Matrix<double, naneye::recon::kCalibrationParameters, naneye::recon::kCalibrationParameters + 3> A;
  for (int i = 0; i < A.size(); ++i) A(i) = std::sin(1.0 + 0.37 * i) * std::pow(10.0, -(i % 5));
  const naneye::recon::CalibrationCovariance cov = A * A.transpose();
  rig.sigmas.covariance = cov;
  const fs::path out = dir_ / "saved.yaml";
  naneye::recon::save_rig(rig, out);
  const auto back = load_rig(out);
  ASSERT_TRUE(back.sigmas.covariance);
  EXPECT_EQ(*back.sigmas.covariance, cov);

  std::ifstream in(out);
  const std::string saved((std::istreambuf_iterator<char>(in)), {});
  const auto with = [&](const naneye::recon::CalibrationCovariance& m) {
    std::string text = saved;
    const auto at = text.find("calibration_covariance:");
    text.erase(at);
    cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    cv::Mat cm;
    cv::eigen2cv(Eigen::MatrixXd(m), cm);
    fs << "calibration_covariance" << cm;
    const std::string extra = fs.releaseAndGetString();
    return write("variant.yaml", text + extra.substr(extra.find("calibration_covariance:")));
  };
  naneye::recon::CalibrationCovariance asym = cov;
  asym(0, 5) += 1e-3 * cov.cwiseAbs().maxCoeff();
  expect_refused(with(asym), {"variant.yaml", "'calibration_covariance'", "not symmetric"});
  naneye::recon::CalibrationCovariance negative = cov;
  negative(3, 3) = -negative(3, 3);
  expect_refused(with(negative), {"'calibration_covariance'", "not positive semi-definite"});
}

// The cross-validation's scale (CalibrationSigmas::covariance_scale) reads back to the bit beside
// its covariance, is not written when 1, and is refused below 1 or without the covariance it scales.
TEST_F(CalibFiles, SigmaScaleRoundTripsAndOnlyWidens) {
  auto rig = load_rig(kDefault);
  Eigen::Matrix<double, naneye::recon::kCalibrationParameters, naneye::recon::kCalibrationParameters> A;
  for (int i = 0; i < A.size(); ++i) A(i) = std::cos(0.3 + 0.71 * i) * std::pow(10.0, -(i % 4));
  rig.sigmas.covariance = A * A.transpose();
  const fs::path plain = dir_ / "plain.yaml", scaled = dir_ / "scaled.yaml";
  naneye::recon::save_rig(rig, plain);
  rig.sigmas.covariance_scale = 2.6371;
  naneye::recon::save_rig(rig, scaled);
  EXPECT_EQ(load_rig(plain).sigmas.covariance_scale, 1.0);
  EXPECT_EQ(load_rig(scaled).sigmas.covariance_scale, 2.6371);
  std::ifstream in(plain);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(text.find("calibration_sigma_scale"), std::string::npos);
  expect_refused(write("below_one.yaml", text + "calibration_sigma_scale: 0.5\n"),
                 {"below_one.yaml", "'calibration_sigma_scale'", "must be >= 1"});
  expect_refused(write("not_a_number.yaml", text + "calibration_sigma_scale: .nan\n"),
                 {"'calibration_sigma_scale'", "non-finite"});
  const std::string marginals_only = text.substr(0, text.find("calibration_covariance:"));
  expect_refused(write("alone.yaml", marginals_only + "calibration_sigma_scale: 2\n"),
                 {"'calibration_sigma_scale'", "without calibration_covariance"});
}

TEST_F(CalibFiles, IntrinsicsAndExtrinsicsInTwoFiles) {
  const auto pos = text_.find("R: !!opencv-matrix");
  const auto sig = text_.find("# One-sigma");
  ASSERT_NE(pos, std::string::npos);
  const std::string header = "%YAML:1.0\n---\n";
  const auto intr = write("intrinsics.yml", text_.substr(0, pos));
  const auto extr = write("extrinsics.yml", header + text_.substr(pos, sig - pos));
  const auto rig = load_rig({intr, extr});
  EXPECT_EQ(rig.R, load_rig(kDefault).R);
  // Either half alone is refused, naming what is missing.
  expect_refused(intr, {"intrinsics.yml", "'R'", "missing"});
}

TEST_F(CalibFiles, ConflictingDuplicateKeyRefused) {
  const auto a = write("a.yml", text_);
  const std::string header = "%YAML:1.0\n---\n";
  const auto b = write(
      "b.yml", header + "T: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ -1., 0., 0. ]\n");
  try {
    load_rig({a, b});
    ADD_FAILURE();
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("b.yml"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("'T'"), std::string::npos);
  }
}

TEST_F(CalibFiles, MissingKeyRefused) {
  expect_refused(variant("M2: !!opencv-matrix", "M9: !!opencv-matrix"), {"variant.yaml", "'M2'", "missing"});
  expect_refused(variant("image_width: 250\n", ""), {"variant.yaml", "'image_width'", "missing"});
}

TEST_F(CalibFiles, WrongShapeRefused) {
  expect_refused(
      variant("rows: 3\n   cols: 3\n   dt: d\n   data: [ 216.360, 0., 122.414, 0., 216.315, 111.535, 0., "
              "0., 1. ]",
              "rows: 2\n   cols: 3\n   dt: d\n   data: [ 216.360, 0., 122.414, 0., 216.315, 111.535 ]"),
      {"variant.yaml", "'M1'", "2x3", "expected 3x3"});
  expect_refused(variant("cols: 5\n   dt: d\n   data: [ -0.369, 0.303, 0., 0., -0.366 ]",
                         "cols: 8\n   dt: d\n   data: [ -0.369, 0.303, 0., 0., -0.366, 0., 0., 0. ]"),
                 {"'D1'", "8 coefficients"});
  expect_refused(variant("data: [ -0.369, 0.303, 0., 0., -0.366 ]", "data: [ -0.369, 0.303, 0., 0. ]"),
                 {"'D1'", "data"});
}

TEST_F(CalibFiles, NonFiniteRefused) {
  expect_refused(variant("-1.0707859762429959", ".nan"), {"variant.yaml", "'T'", "non-finite"});
}

TEST_F(CalibFiles, NotARotationRefused) {
  expect_refused(variant("0.99932889072470799", "0.9"), {"variant.yaml", "'R'", "not a rotation"});
}

TEST_F(CalibFiles, BadCameraMatrixRefused) {
  expect_refused(variant("216.360, 0., 122.414", "-216.360, 0., 122.414"), {"'M1'", "positive"});
}

TEST_F(CalibFiles, ImageSizeMustBeStated) {
  expect_refused(variant("image_height: 250\n", ""), {"'image_height'", "missing"});
  expect_refused(variant("image_width: 250", "image_width: 250.5"), {"'image_width'", "integer"});
  // A different sensor (160 x 160) is accepted when the file says so.
  const auto rig =
      load_rig(variant("image_width: 250\nimage_height: 250", "image_width: 160\nimage_height: 160"));
  EXPECT_EQ(rig.left.width(), 160);
}

TEST_F(CalibFiles, UnreadableFilesRefused) {
  expect_refused(dir_ / "absent.yaml", {"absent.yaml", "not found"});
  const auto garbage = write("garbage.yaml", "this: [is: not, {valid\n");
  EXPECT_THROW(load_rig(garbage), CalibrationError);
  expect_refused(variant("0.579, 0., 0.758", "-0.579, 0., 0.758"), {"'M1_sigma'", "negative"});
}

TEST_F(CalibFiles, WhatOpenCvsFileStorageWritesIsRead) {
  // Every element type a FileStorage matrix has, its strings and sequences (skipped), and its
  // spelling of a NaN (.Nan), which must be refused as such rather than misread.
  const auto rig = load_rig(kDefault);
  const fs::path out = dir_ / "opencv.yaml";
  {
    cv::FileStorage f(out.string(), cv::FileStorage::WRITE);
    f << "calibration_time"
      << "Wed Dec  2 12:00:00 2026"
      << "views" << std::vector<int>{1, 2, 3};
    f << "image_width" << 250 << "image_height" << 250;
    cv::Mat m1, m2, d1, d2, r, t;
    cv::eigen2cv(rig.left.K(), m1);
    cv::eigen2cv(rig.right.K(), m2);
    cv::eigen2cv(Eigen::MatrixXd(rig.left.distortion().opencv_order()), d1);
    cv::eigen2cv(Eigen::MatrixXd(rig.right.distortion().opencv_order()), d2);
    cv::eigen2cv(rig.R, r);
    cv::eigen2cv(rig.T, t);
    m1.convertTo(m1, CV_32F);
    f << "M1" << m1 << "M2" << m2 << "D1" << d1 << "D2" << d2 << "R" << r << "T" << t;
    const cv::Mat board = (cv::Mat_<int>(1, 2) << 6, 8);
    const cv::Mat mask = (cv::Mat_<uchar>(1, 2) << 0, 255);
    f << "board" << board << "mask" << mask;
  }
  const auto back = load_rig(out);
  EXPECT_EQ(back.left.fx(), static_cast<double>(static_cast<float>(rig.left.fx())));
  EXPECT_EQ(back.right.K(), rig.right.K());
  EXPECT_EQ(back.T, rig.T);

  cv::FileStorage f((dir_ / "nan.yaml").string(), cv::FileStorage::WRITE);
  const cv::Mat nan_t = (cv::Mat_<double>(3, 1) << std::nan(""), 0, 0);
  f << "T" << nan_t;
  f.release();
  std::ifstream in(dir_ / "nan.yaml");
  const std::string nan_text(std::istreambuf_iterator<char>(in), {});
  ASSERT_NE(nan_text.find(".Nan"), std::string::npos) << nan_text;
  const auto nan_file = write("with-nan.yaml", text_.substr(0, text_.find("T: !!opencv-matrix")) +
                                                   nan_text.substr(nan_text.find("T: !!opencv-matrix")));
  expect_refused(nan_file, {"with-nan.yaml", "'T'", "non-finite"});
}

TEST_F(CalibFiles, TheFileMustBeFileStorageYaml) {
  expect_refused(variant("%YAML:1.0\n", ""), {"variant.yaml", "%YAML:1.0"});
  expect_refused(write("json.yaml", "{\"M1\": {\"rows\": 1}}\n"), {"json.yaml", "%YAML:1.0"});
  expect_refused(write("empty.yaml", "%YAML:1.0\n---\n"), {"empty.yaml", "no keys"});
  expect_refused(write("two.yaml", text_ + "---\nimage_width: 250\n"),
                 {"two.yaml", "more than one YAML document"});
  expect_refused(write("nul.yaml", text_ + std::string(1, '\0')), {"nul.yaml", "NUL"});
  // yaml-cpp's own refusal, with the file's line number (the header line counts).
  expect_refused(write("broken.yaml", "%YAML:1.0\n---\nM1: [1, 2\n"),
                 {"broken.yaml", "line 4", "not valid YAML"});
  // The file on which OpenCV 4.6's FileStorage::open looped forever (fuzz_calib_yaml).
  expect_refused(fs::path(NANEYE_SOURCE_DIR) / "tests/fuzz/corpus/calib_yaml/hang_filestorage_loop.yaml",
                 {"hang_filestorage_loop.yaml", "not valid YAML"});
  // ... and the one on which yaml-cpp 0.7's LoadAll looped (a `,` outside a flow collection, which
  // yaml-cpp took for endless empty documents), and the smallest file of that shape: not YAML.
  expect_refused(fs::path(NANEYE_SOURCE_DIR) / "tests/fuzz/corpus/calib_yaml/hang_yamlcpp_loadall.yaml",
                 {"hang_yamlcpp_loadall.yaml", "line 1", "not valid YAML"});
  expect_refused(write("comma.yaml", "%YAML:1.0\n---\n,\n"), {"comma.yaml", "line 3", "not valid YAML"});
  // Not UTF-8 (a Latin-1 comment): the parser's own refusal, named.
  expect_refused(write("latin1.yaml", text_ + "# 5.99 \xb5m\n"), {"latin1.yaml", "not valid YAML", "UTF-8"});
  // A %TAG directive: libyaml copies its prefix into every tag that uses the handle, so a 1 MiB file
  // of a 500 kB prefix and 60 000 short tagged nodes held the reader for minutes and gigabytes.
  // FileStorage writes none; the reader refuses it at the document's start.
  expect_refused(fs::path(NANEYE_SOURCE_DIR) / "tests/fuzz/corpus/calib_yaml/tag_directive.yaml",
                 {"tag_directive.yaml", "line 2", "not valid YAML", "%TAG"});
  std::string bomb = "%YAML:1.0\n%TAG !a! tag:" + std::string(500000, 'x') + "\n---\nimage_width:\n";
  for (int i = 0; i < 60000; ++i) bomb += "- !a!y 1\n";
  expect_refused(write("tag_bomb.yaml", bomb), {"tag_bomb.yaml", "%TAG"});
}

TEST_F(CalibFiles, ATextIsReadAsItsFileIs) {
  // parse_rig takes what load_rig would read: the same rig, and errors under the name given.
  const std::string& text = text_;  // kDefault's
  const auto from_text = naneye::recon::parse_rig({{"paper", text}});
  const auto from_file = load_rig(kDefault);
  EXPECT_EQ(from_text.left.K(), from_file.left.K());
  EXPECT_EQ(from_text.T, from_file.T);
  std::string renamed = text;
  renamed.replace(renamed.find("image_width"), 11, "image_wide_");
  try {
    const auto tried = naneye::recon::try_parse_rig({{"given.yaml", renamed}});
    EXPECT_FALSE(tried.rig.has_value());
    naneye::recon::parse_rig({{"given.yaml", renamed}});
    ADD_FAILURE() << "a text without its keys was read";
  } catch (const naneye::recon::CalibrationError& e) {
    // The refusal try_parse_rig returns is what parse_rig throws.
    EXPECT_EQ(naneye::recon::try_parse_rig({{"given.yaml", renamed}}).refusal, e.what());
    EXPECT_NE(std::string(e.what()).find("given.yaml: key 'image_width': missing"), std::string::npos)
        << e.what();
  }
}

TEST_F(CalibFiles, AMatrixNeedsRowsColsASingleChannelTypeAndNumbers) {
  expect_refused(variant("   dt: d\n   data: [ -0.369", "   data: [ -0.369"), {"'D1'", "no 'dt'", "line 15"});
  expect_refused(variant("   dt: d\n   data: [ -0.369", "   dt: 3d\n   data: [ -0.369"),
                 {"'D1'", "'3d'", "single-channel"});
  expect_refused(variant("data: [ -0.369, 0.303", "data: [ -0.369, \"0.303\""),
                 {"'D1'", "data value 2", "not a number"});
  expect_refused(variant("data: [ -0.369, 0.303", "data: [ -0.369, 0x1f"),
                 {"'D1'", "data value 2", "'0x1f'"});
  expect_refused(variant("   dt: d\n   data: [ -0.369", "   dt: i\n   data: [ -0.369"),
                 {"'D1'", "not an integer", "dt 'i'"});
  expect_refused(variant("   rows: 1\n   cols: 5", "   rows: 1\n   rows: 1\n   cols: 5"),
                 {"'D1'", "'rows' given twice"});
  expect_refused(variant("   rows: 1\n   cols: 5", "   rows: -1\n   cols: 5"),
                 {"'D1'", "'rows'", "positive integer"});
  expect_refused(variant("D1: !!opencv-matrix", "D1: !!opencv-nd-matrix"), {"'D1'", "not an opencv-matrix"});
}

TEST_F(CalibFiles, AKeyWeNeedThatIsNotANumberIsNamedAsSuch) {
  expect_refused(variant("image_width: 250", "image_width: \"250\""),
                 {"variant.yaml", "'image_width'", "a string ('250')", "not a number"});
  expect_refused(variant("image_width: 250", "image_width: [ 250 ]"), {"'image_width'", "a sequence"});
  // YAML's nulls (nothing, ~, null) are empty; a quoted one is a string.
  for (const char* null_value : {"", " ~", " null", " NULL"})
    expect_refused(variant("image_width: 250", std::string("image_width:") + null_value),
                   {"'image_width'", "empty"});
  expect_refused(variant("image_width: 250", "image_width: \"~\""), {"'image_width'", "a string ('~')"});
  // Numbers as FileStorage and people write them: a sign, an exponent, a trailing point.
  const auto rig = load_rig(variant("216.360, 0., 122.414", "+2.1636e+02, 0, 122.414"));
  EXPECT_DOUBLE_EQ(rig.left.fx(), 216.36);
  // A YAML alias is the value its anchor names (a matrix or a number), as FileStorage reads it.
  const auto aliased =
      load_rig(variant("image_width: 250\nimage_height: 250", "image_width: &side 250\nimage_height: *side"));
  EXPECT_EQ(aliased.left.height(), 250);
  expect_refused(variant("image_height: 250", "image_height: *nowhere"), {"variant.yaml", "not valid YAML"});
}
