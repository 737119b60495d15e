// The whole calibration path on rendered images: the simulator renders the paper's Dataset 3 rig with
// its sensor noise, the corner detector (modelling the lenses with a deliberately wrong guess) finds the
// boards, the bundle recovers the rig. The truth must lie within 3 sigma of every estimate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "calib_scene.hpp"
#include "naneye/recon/calibrate/bundle.hpp"
#include "naneye/recon/corners/detector.hpp"
#include "naneye/recon/corners/stereo_ids.hpp"

using namespace naneye;

namespace {

// The truth with every intrinsic a little off: what a user's nominal calibration would be.
recon::StereoRig wrong_guess(const recon::StereoRig& truth) {
  recon::StereoRig g = truth;
  for (auto* cam : {&g.left, &g.right}) {
    Eigen::Matrix3d K = cam->K();
    K(0, 0) *= 1.02;
    K(1, 1) *= 1.02;
    K(0, 2) += 2;
    K(1, 2) -= 2;
    recon::Distortion d = cam->distortion();
    d.k1 += 0.02;
    *cam = recon::CameraModel(K, d, 250, 250);
  }
  return g;
}

}  // namespace

TEST(CalibrateRendered, Dataset3WithinThreeSigma) {
  const recon::StereoRig& truth = test::paper_d3();
  const recon::StereoRig guess = wrong_guess(truth);
  sim::Renderer renderer(truth, sim::SceneSettings{}, sim::SensorSettings{});
  recon::CornerDetector left(guess.left), right(guess.right);
  recon::CornerResult l, r;
  std::vector<recon::CalibrationView> views;
  sim::Rng rng(5);
  for (const auto& pose : test::sample_poses(truth, 12, 9)) {
    const sim::RenderedPair img = renderer.render(pose, rng);
    if (!left.detect_full(sim::raw_view(img.left), l) || !right.detect_full(sim::raw_view(img.right), r))
      continue;
    const auto ids = recon::resolve_stereo_ids(guess, l, r);
    if (ids.status != recon::StereoIdStatus::consistent && ids.status != recon::StereoIdStatus::flipped_right)
      continue;
    recon::CalibrationView v;
    for (int i = 0; i < l.count; ++i) v.left.push_back({l.corners[i].row, l.corners[i].col, l.corners[i].px});
    for (int i = 0; i < r.count; ++i)
      v.right.push_back({r.corners[i].row, r.corners[i].col, r.corners[i].px});
    views.push_back(std::move(v));
  }
  ASSERT_GE(views.size(), 10u);
  recon::CalibrationSettings s;
  s.initial = &guess;
  const auto res = recon::calibrate_stereo(views, test::recon_board(), s);
  ASSERT_TRUE(res.ok) << res.message;
  std::printf("%zu views: RMS %.4f px per corner, worst %.4f px, sigma %.4f px, initial RMS %.3f px\n",
              views.size(), res.rms_px, res.worst_px, res.sigma_px, res.initial_rms_px);
  std::vector<double> want;
  for (const auto* cam : {&truth.left, &truth.right}) {
    const auto in = recon::bundle::intrinsics_of(*cam);
    want.insert(want.end(), in.begin(), in.end());
  }
  const Eigen::Vector3d om = recon::rodrigues(truth.R);
  for (int a = 0; a < 3; ++a) want.push_back(om(a));
  for (int a = 0; a < 3; ++a) want.push_back(truth.T(a));
  std::printf("%-10s %12s %12s %10s %8s\n", "parameter", "truth", "estimate", "sigma", "z");
  for (std::size_t i = 0; i < want.size(); ++i) {
    const auto& p = res.parameters[i];
    if (p.fixed) continue;
    const double z = (p.value - want[i]) / p.sigma;
    std::printf("%-10s %12.6f %12.6f %10.6f %8.2f\n", p.name.c_str(), want[i], p.value, p.sigma, z);
    EXPECT_LE(std::abs(z), 3.0) << p.name;
  }
  // The renders' corners are good to a few hundredths of a pixel.
  EXPECT_LT(res.rms_px, 0.1);
  EXPECT_LT(res.find("left.fx")->sigma, 1.0);
}
