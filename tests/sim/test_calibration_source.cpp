// sim://dark and sim://flat: the sensor's calibration frames through the driver's own path, from
// the same die as every other render of the same sensor: `naneye fixed-pattern` on them measures
// the die's DSNU and PRNU (recon/camera/fixed_pattern.hpp), and sensor=measured gives the real
// NanEye's figures to any preset.
#include <gtest/gtest.h>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/fixed_pattern.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::sim::calibration_source_test {
namespace {

driver::SourceRegistry registry() {
  driver::SourceRegistry r = driver::make_default_registry();
  register_sim_source(r);
  return r;
}

// The source's pairs fed to one builder per eye; returns the pair count.
int feed(const std::string& uri, bool dark, recon::FixedPatternBuilder& left,
         recon::FixedPatternBuilder& right) {
  auto src = registry().open(uri);
  src->start();
  int n = 0;
  while (auto p = src->next(std::chrono::milliseconds(10000))) {
    for (int eye = 0; eye < 2; ++eye) {
      recon::RawImageView v;
      v.data = (eye == 0 ? p->left : p->right).pixels.data();
      auto& b = eye == 0 ? left : right;
      dark ? b.add_dark(v) : b.add_flat(v);
    }
    ++n;
  }
  src->stop();
  return n;
}

TEST(SimCalibrationSource, TheMeasuredDiesPatternComesOutOfDarkAndFlatFrames) {
  recon::FixedPatternBuilder left, right;
  EXPECT_EQ(feed("sim://dark?sensor=measured&pairs=24&speed=max", true, left, right), 24);
  EXPECT_EQ(feed("sim://flat?sensor=measured&pairs=24&speed=max&seed=2", false, left, right), 24);
  for (const auto* b : {&left, &right}) {
    const recon::FixedPattern p = b->build();
    // SensorSettings::measured: DSNU 3.8 DN with column FPN 0.55 DN, PRNU 2 %, read noise 2.5 DN.
    EXPECT_NEAR(p.dsnu_dn, 3.84, 0.25);
    EXPECT_NEAR(p.prnu, 0.02, 0.003);
    EXPECT_NEAR(p.dark_se_dn, 2.5 / std::sqrt(24.0), 0.05);
  }
  // The default sensor has no fixed pattern: its dark frames spread by the read noise / sqrt(n) only.
  recon::FixedPatternBuilder l2, r2;
  feed("sim://dark?pairs=16&speed=max", true, l2, r2);
  EXPECT_LT(l2.build().dsnu_dn, 0.8);
}

TEST(SimCalibrationSource, RefusesWhatTheFramesCannotHave) {
  const auto r = registry();
  EXPECT_THROW(r.open("sim://dark?motion=orbit"), driver::SourceError);
  EXPECT_THROW(r.open("sim://sphere?sensor=old"), driver::SourceError);
  EXPECT_THROW(r.open("sim://flat?sensor=measured&noise=0"), driver::SourceError);
  EXPECT_NO_THROW(r.open("sim://sphere?sensor=measured&pairs=1"));
  EXPECT_NO_THROW(r.open("sim://paper-d3?sensor=measured&pairs=1"));
}

}  // namespace
}  // namespace naneye::sim::calibration_source_test
