// Is the dense map's sigma the spread of its error? A Monte Carlo check in mrcal's manner: the same
// textured scene rendered K times with K noise seeds and once without noise. Per pixel valid in
// every noisy render: the spread of Z over the seeds (the noise's part of the error) against the
// stated sigma, the noise-free render's error (the method's misfit: resampling, the window model)
// against the same sigma, and the plain rms(err / sigma) the tests hold to 0.7-1.4.
//   build/bench/bench_dense_sigma [--seeds K] [--real-sensor] [--no-fpn] [--max-radius R] [--max-sigma S]
//                                 [--pattern dsnu|prnu|as-read-noise] [--fixed-pattern N]
// --real-sensor: the real NanEye's measured noise, blur and fixed patterns (SensorSettings::measured),
// where the matcher widens its window (the r column: the radius the last noisy render was matched with).
// --no-fpn: without the fixed pattern (column FPN, DSNU, PRNU), to tell its share of the misfit.
// --max-radius R: the largest window the matcher may choose (R = 3: the fixed window).
// --max-sigma S: the matcher's sigma bound, px (MatcherSettings::max_sigma_px).
// --pattern dsnu | prnu | as-read-noise: with --real-sensor, only the DSNU or only the PRNU of the
// fixed pattern, or none of it but the DSNU's variance added to the read noise (temporal): does a
// fixed pattern hurt the sigma more than temporal noise of the same variance?
// --fixed-pattern N: the die's fixed pattern measured from N capped and N flat frames and removed
// from every render first, as naneyed's [sensor] fixed_pattern does (docs/sensor-calibration.md).
// An honest sigma gives rms(spread / sigma) ~ 1; the misfit is not noise and is not in the sigma.
// p68, tail and core/s tell a sigma too small for every pixel from one right for most but with a few
// gross errors: the 68.27 % quantile of |err / sigma| (1 for a Gaussian), the share beyond 4 sigma,
// and the rms of the rest.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "../tests/support/seed_spread.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/scene/dense.hpp"
#include "naneye/recon/scene/sparse.hpp"
#include "naneye/sim/flat_field.hpp"
#include "naneye/sim/textured.hpp"

using namespace naneye;

namespace {

// |err| / sigma beyond which an error counts as the tail: a Gaussian passes 4 sigma once in ~16 000.
constexpr float kTail = 4.f;

struct Case {
  const char* label;
  const char* preset;
  bool bayer;
  double white_dn;         // DN; the exposure (the default's white is 760)
  double contrast_factor;  // times the preset's texture contrast
};

void run(const recon::StereoRig& rig, const Case& c, int seeds, bool real_sensor, bool no_fpn,
         const std::string& pattern, int pattern_frames, const recon::scene::DenseSettings& ds) {
  sim::SensorSettings sensor = real_sensor ? sim::SensorSettings::measured(c.bayer) : sim::SensorSettings{};
  if (no_fpn) sensor.column_fpn_dn = sensor.dsnu_dn = sensor.prnu = 0;
  if (pattern == "dsnu") sensor.prnu = sensor.column_fpn_dn = 0;
  if (pattern == "prnu") sensor.dsnu_dn = sensor.column_fpn_dn = 0;
  if (pattern == "as-read-noise") {  // the DSNU's variance as temporal noise instead: fixed or not?
    sensor.read_noise_dn = std::hypot(sensor.read_noise_dn, sensor.dsnu_dn);
    sensor.dsnu_dn = sensor.prnu = sensor.column_fpn_dn = 0;
  }
  sensor.bayer = c.bayer;
  sensor.white_dn = c.white_dn;
  sim::TexturedSceneSettings scene = *sim::textured_preset(c.preset);
  scene.texture.contrast *= c.contrast_factor;
  // --fixed-pattern N: measured from N capped and N flat frames of the same die, removed from every
  // render (docs/sensor-calibration.md).
  const recon::StereoFixedPattern fixed =
      pattern_frames > 0 ? sim::measure_fixed_pattern(sensor, pattern_frames, 0.7, 0xF1A7)
                         : recon::StereoFixedPattern{};
  std::vector<std::uint16_t> fixed_left, fixed_right;
  recon::scene::SparseReconstructor luma(rig);
  recon::scene::DenseReconstructor dense(rig, ds);
  recon::scene::DepthMap map;
  std::optional<test::SeedSpread> tally;
  double misfit2 = 0;
  int misfit_n = 0, radius = 0;
  for (int k = 0; k <= seeds; ++k) {
    sim::SensorSettings s = sensor;
    s.noise = k < seeds;  // the last render without noise
    const sim::TexturedRenderer renderer(rig, s);
    sim::Rng rng(1000 + static_cast<std::uint64_t>(k));
    const sim::TexturedPair p = renderer.render(scene, rng);
    recon::RawImageView lv = sim::raw_view(p.left, c.bayer), rv = sim::raw_view(p.right, c.bayer);
    sim::remove_fixed_pattern(fixed, lv, rv, fixed_left, fixed_right);
    luma.load_luma(lv, rv);
    dense.reconstruct(luma.luma(), map);
    if (k < seeds) radius = dense.matcher().radius_used();
    if (!tally) tally.emplace(static_cast<std::size_t>(map.width) * map.height, seeds);
    for (int r = 0; r < map.height; ++r)
      for (int col = 0; col < map.width; ++col) {
        const std::size_t i = static_cast<std::size_t>(r) * map.width + col;
        const double z = map.z_at(col, r), zt = p.depth.at<double>(r, col);
        const bool ok = std::isfinite(z) && std::isfinite(zt);
        if (k < seeds) {
          if (ok)
            tally->add(i, k, z, map.sigma_at(col, r), zt);
          else
            tally->drop(i);  // out for good: the figures are over pixels valid in every render
        } else if (ok && tally->complete(i)) {
          misfit2 += (z - zt) * (z - zt) / tally->mean_sigma2(i);
          ++misfit_n;
        }
      }
  }
  const test::SeedSpread::Summary f = tally->summary(kTail);
  std::printf("%-18s %-5s %2d %7d %8.3f %9.3f %8.3f %6.3f %7.3f%% %8.3f\n", c.label,
              c.bayer ? "bayer" : "mono", radius, f.pixels, f.spread,
              std::sqrt(misfit2 / std::max(1, misfit_n)), f.err, f.p68, 100.0 * f.tail_share, f.core);
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 8;
  bool real_sensor = false, no_fpn = false;
  std::string pattern = "all";
  int pattern_frames = 0;
  recon::scene::DenseSettings ds;
  for (int a = 1; a < argc; ++a) {
    if (a + 1 < argc && std::strcmp(argv[a], "--seeds") == 0) seeds = std::max(2, std::atoi(argv[a + 1]));
    if (std::strcmp(argv[a], "--real-sensor") == 0) real_sensor = true;
    if (std::strcmp(argv[a], "--no-fpn") == 0) no_fpn = true;
    if (a + 1 < argc && std::strcmp(argv[a], "--max-radius") == 0)
      ds.matcher.max_radius = std::atoi(argv[a + 1]);
    if (a + 1 < argc && std::strcmp(argv[a], "--max-sigma") == 0)
      ds.matcher.max_sigma_px = std::atof(argv[a + 1]);
    if (a + 1 < argc && std::strcmp(argv[a], "--pattern") == 0) pattern = argv[a + 1];
    if (a + 1 < argc && std::strcmp(argv[a], "--fixed-pattern") == 0) pattern_frames = std::atoi(argv[a + 1]);
  }
  const recon::StereoRig rig =
      recon::load_rig(std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml");
  std::printf("%d noise seeds per case; figures over the pixels valid in every noisy render\n", seeds);
  std::printf("%-18s %-5s %2s %7s %8s %9s %8s %6s %8s %8s\n", "case", "", "r", "pixels", "spread/s",
              "misfit/s", "err/s", "p68", "tail", "core/s");
  const Case cases[] = {
      {"plane", "plane", false, 760, 1},
      {"sphere", "sphere", false, 760, 1},
      {"tube", "tube", false, 760, 1},
      {"height", "height", false, 760, 1},
      {"sphere dim, low", "sphere", false, 300, 0.5},
      {"plane", "plane", true, 760, 1},
      {"sphere", "sphere", true, 760, 1},
  };
  for (const Case& c : cases) run(rig, c, seeds, real_sensor, no_fpn, pattern, pattern_frames, ds);
  return 0;
}
