// recon::rig_problem: the calibration checks naneyed (start, SIGHUP, --check-config) and
// `naneye calib info|export` share. Each defect is refused with its reason; the paper's passes.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/camera/rig_validate.hpp"

using naneye::recon::CameraModel;
using naneye::recon::rig_problem;
using naneye::recon::StereoRig;

namespace {

StereoRig paper() {
  return naneye::recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
}

std::string problem_of(const StereoRig& r) {
  return rig_problem(r).value_or("(accepted)");
}

}  // namespace

TEST(RigValidate, ThePaperCalibrationPasses) {
  EXPECT_EQ(rig_problem(paper()), std::nullopt);
}

TEST(RigValidate, AbsurdDistortionAndValuesThatAreNotFiniteAreNamed) {
  const StereoRig good = paper();
  StereoRig r = good;
  auto d = good.right.distortion();
  d.k1 = 1e300;  // `naneye calib info` described this one
  r.right = CameraModel(good.right.K(), d);
  EXPECT_NE(problem_of(r).find("right camera: distortion coefficient 1e+300 beyond +-100"), std::string::npos)
      << problem_of(r);
  r = good;
  d = good.left.distortion();
  d.p2 = std::nan("");
  r.left = CameraModel(good.left.K(), d);
  EXPECT_NE(problem_of(r).find("left camera: a distortion coefficient is not finite"), std::string::npos)
      << problem_of(r);
  r = good;
  r.T.x() = std::numeric_limits<double>::infinity();
  EXPECT_NE(problem_of(r).find("relative pose has a value that is not finite"), std::string::npos);
}

TEST(RigValidate, SizesFocalLengthsAndPrincipalPointsOutsideTheirRangeAreNamed) {
  const StereoRig good = paper();
  StereoRig r = good;
  r.left = CameraModel(good.left.K(), good.left.distortion(), 100000, 250);
  EXPECT_NE(problem_of(r).find("image size 100000x250 outside 16..4096 px"), std::string::npos)
      << problem_of(r);
  r = good;
  Eigen::Matrix3d K = good.left.K();
  K(1, 1) = 20000;
  r.left = CameraModel(K, good.left.distortion());
  EXPECT_NE(problem_of(r).find("focal length 20000 px outside 10..10000"), std::string::npos)
      << problem_of(r);
  K = good.left.K();
  K(0, 2) = 260;  // 250 px wide: centres run -0.5..249.5
  r.left = CameraModel(K, good.left.distortion());
  EXPECT_NE(problem_of(r).find("principal point (260,"), std::string::npos) << problem_of(r);
}

TEST(RigValidate, ADomainThatIsASpeckIsRefused) {
  // k1 = -50: the radial model folds ~12 px from the centre (the paper's left camera: 139 px), so
  // almost no pixel could be measured.
  const StereoRig good = paper();
  StereoRig r = good;
  auto d = good.left.distortion();
  d.k1 = -50;
  r.left = CameraModel(good.left.K(), d);
  ASSERT_TRUE(r.left.fold_radius_px().has_value());
  EXPECT_LT(*r.left.fold_radius_px(), 25.0);
  EXPECT_NE(problem_of(r).find("left camera: the distortion model folds"), std::string::npos)
      << problem_of(r);
  EXPECT_NE(problem_of(r).find("valid domain under 25 px"), std::string::npos) << problem_of(r);
}

TEST(RigValidate, APoseThatIsNoRotationOrNoBaselineIsRefused) {
  const StereoRig good = paper();
  StereoRig r = good;
  r.R(0, 0) *= 2;
  EXPECT_NE(problem_of(r).find("R is not a rotation"), std::string::npos) << problem_of(r);
  r = good;
  r.R = -good.R;  // orthogonal, det -1: a reflection
  EXPECT_NE(problem_of(r).find("R is not a rotation"), std::string::npos) << problem_of(r);
  r = good;
  r.T = Eigen::Vector3d::Zero();
  EXPECT_NE(problem_of(r).find("baseline 0 mm outside 0.01..100 mm"), std::string::npos) << problem_of(r);
}
