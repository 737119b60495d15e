// The calibration bundle on exact projections of the paper's Dataset 3 rig with white corner noise of
// a known sigma: the Jacobian, the recovered parameters against the truth and their sigmas, the options,
// the refusals and the YAML round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "calib_scene.hpp"
#include "naneye/recon/calibrate/bundle.hpp"

using namespace naneye;

namespace {

constexpr double kNoisePx = 0.1;

// The truth as the flat parameter list of CalibrationResult (left intrinsics, right, om, T).
std::vector<double> truth_values(const recon::StereoRig& rig) {
  std::vector<double> v;
  for (const auto* cam : {&rig.left, &rig.right}) {
    const auto in = recon::bundle::intrinsics_of(*cam);
    v.insert(v.end(), in.begin(), in.end());
  }
  const Eigen::Vector3d om = recon::rodrigues(rig.R);
  for (int a = 0; a < 3; ++a) v.push_back(om(a));
  for (int a = 0; a < 3; ++a) v.push_back(rig.T(a));
  return v;
}

struct Fixture {
  std::vector<recon::CalibrationView> views;
  recon::CalibrationResult result;
};

const Fixture& d3_calibration() {
  static const Fixture f = [] {
    Fixture f;
    f.views = test::noisy_views(test::paper_d3(), test::sample_poses(test::paper_d3(), 16, 7), kNoisePx, 8);
    f.result = recon::calibrate_stereo(f.views, test::recon_board(), {});
    return f;
  }();
  return f;
}

}  // namespace

TEST(CalibrateBundle, JacobianMatchesCentralDifferences) {
  const auto views = test::noisy_views(test::paper_d3(), test::sample_poses(test::paper_d3(), 3, 3), 0.1, 4);
  recon::CalibrationSettings s;
  s.tangential = true;  // every intrinsic column present
  const auto layout = recon::bundle::make_layout(s, 3);
  std::string error;
  auto st = recon::bundle::initial_state(views, test::recon_board(), s, error);
  ASSERT_TRUE(st) << error;
  st->cam[0][6] = 0.002;  // non-zero tangential terms so that their cross terms are exercised
  st->cam[1][7] = -0.003;
  Eigen::VectorXd r, rp, rm;
  Eigen::MatrixXd J;
  recon::bundle::evaluate(*st, layout, views, test::recon_board(), 250, 250, r, &J);
  ASSERT_EQ(J.cols(), 18 + 6 + 18);
  double worst = 0;
  for (int c = 0; c < layout.columns; ++c) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(layout.columns);
    const double h = c < 18 && (c % 9) < 4 ? 1e-4 : 1e-6;  // pixels-sized intrinsics take a larger step
    d(c) = h;
    recon::bundle::evaluate(recon::bundle::apply(*st, layout, d), layout, views, test::recon_board(), 250,
                            250, rp, nullptr);
    d(c) = -h;
    recon::bundle::evaluate(recon::bundle::apply(*st, layout, d), layout, views, test::recon_board(), 250,
                            250, rm, nullptr);
    const Eigen::VectorXd numeric = (rp - rm) / (2 * h);
    const double scale = std::max(1.0, numeric.cwiseAbs().maxCoeff());
    worst = std::max(worst, (numeric - J.col(c)).cwiseAbs().maxCoeff() / scale);
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(CalibrateStereo, RecoversDataset3WithinThreeSigma) {
  const auto& f = d3_calibration();
  const auto& res = f.result;
  ASSERT_TRUE(res.ok) << res.message;
  const auto truth = truth_values(test::paper_d3());
  ASSERT_EQ(res.parameters.size(), truth.size());
  std::printf("%-10s %12s %12s %10s %8s\n", "parameter", "truth", "estimate", "sigma", "z");
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const auto& p = res.parameters[i];
    const double z = p.sigma > 0 ? (p.value - truth[i]) / p.sigma : 0.0;
    std::printf("%-10s %12.6f %12.6f %10.6f %8.2f\n", p.name.c_str(), truth[i], p.value, p.sigma, z);
    if (p.fixed) {
      EXPECT_EQ(p.value, truth[i]) << p.name;  // p1 = p2 = 0, fixed
      EXPECT_EQ(p.sigma, 0.0) << p.name;
      continue;
    }
    EXPECT_GT(p.sigma, 0.0) << p.name;
    EXPECT_LE(std::abs(p.value - truth[i]), 3 * p.sigma) << p.name;
  }
  // Plausible sigmas: a 16-view calibration pins the focal lengths to well under a pixel.
  EXPECT_LT(res.find("left.fx")->sigma, 1.0);
  EXPECT_LT(res.find("right.fy")->sigma, 1.0);
  EXPECT_LT(res.find("T.x")->sigma, 0.1);
  // The residual matches the noise that was added: sigma per coordinate, sqrt(2) sigma per corner
  // (less the share of the freedom the fit absorbs).
  EXPECT_NEAR(res.sigma_px, kNoisePx, 0.1 * kNoisePx);
  EXPECT_NEAR(res.rms_px, std::sqrt(2.0) * kNoisePx, 0.15 * kNoisePx);
  EXPECT_GT(res.worst_px, res.rms_px);
  EXPECT_LT(res.worst_px, 6 * kNoisePx);
  ASSERT_EQ(res.views.size(), f.views.size());
  for (const auto& v : res.views) {
    EXPECT_EQ(v.left_corners, 48);
    EXPECT_GT(v.rms_px, 0.5 * kNoisePx);
    EXPECT_LT(v.rms_px, 3 * kNoisePx);
  }
  // The sigma entries of the rig are the parameters' sigmas.
  EXPECT_EQ((*res.rig.sigmas.M1)(0, 0), res.find("left.fx")->sigma);
  EXPECT_EQ((*res.rig.sigmas.M2)(1, 2), res.find("right.cy")->sigma);
  EXPECT_EQ((*res.rig.sigmas.D1)(4), res.find("left.k3")->sigma);
  EXPECT_EQ((*res.rig.sigmas.om)(2), res.find("om.z")->sigma);
  EXPECT_EQ((*res.rig.sigmas.T)(0), res.find("T.x")->sigma);
  EXPECT_EQ((*res.rig.sigmas.M1)(0, 1), 0.0);  // skew is fixed at 0
}
