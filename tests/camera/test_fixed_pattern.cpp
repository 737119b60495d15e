// The sensor's fixed pattern (recon/camera/fixed_pattern.hpp): maps measured from frames with a
// known pattern come back within the error they report, shading stays out of the gain, defects stay
// for the defect test, and a frame with the pattern removed differs from the clean one by the
// noise alone. The frames here are made directly (per-pixel offsets, gains and normal noise at the
// real NanEye's figures, ../shared/notes/measurements.md), not through the simulator.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

#include "naneye/recon/camera/fixed_pattern_io.hpp"

namespace naneye::fixed_pattern_test {
namespace {

constexpr int kSide = 250;
constexpr double kBlack = 48, kDsnu = 3.8, kPrnu = 0.02, kReadNoise = 2.5, kGainEPerDn = 7.1;

// A die: per-pixel offset and gain, two defects (hot and dead), and the frames it gives.
struct Die {
  std::vector<double> offset, gain;
  std::mt19937_64 rng{42};
  bool bayer = false;
  Die() {
    std::normal_distribution<double> n(0, 1);
    offset.resize(kSide * kSide);
    gain.resize(kSide * kSide);
    for (int p = 0; p < kSide * kSide; ++p) {
      offset[static_cast<std::size_t>(p)] = kBlack + kDsnu * n(rng);
      gain[static_cast<std::size_t>(p)] = 1 + kPrnu * n(rng);
    }
  }
  // light(r, c): the clean signal in DN; noise: shot + read (temporal).
  template <class Light>
  std::vector<std::uint16_t> frame(Light light, bool noise = true) {
    std::normal_distribution<double> n(0, 1);
    std::vector<std::uint16_t> f(kSide * kSide);
    for (int r = 0; r < kSide; ++r)
      for (int c = 0; c < kSide; ++c) {
        const auto k = static_cast<std::size_t>(r * kSide + c);
        const double s = light(r, c) * gain[k];
        double v = offset[k] + s;
        if (noise) v += std::sqrt(s / kGainEPerDn + kReadNoise * kReadNoise) * n(rng);
        f[k] = static_cast<std::uint16_t>(std::clamp(std::lround(v), 0L, 1023L));
      }
    f[100 * kSide + 100] = 1023;  // hot
    f[150 * kSide + 50] = 0;      // dead
    return f;
  }
  recon::RawImageView view(const std::vector<std::uint16_t>& f) const {
    recon::RawImageView v;
    v.data = f.data();
    v.layout = bayer ? recon::PixelLayout::bayer_grbg : recon::PixelLayout::mono;
    return v;
  }
};

// The flat: ~500 DN at the centre falling to ~300 at the corners (cos^4 at f = 216 px).
double shaded(int r, int c) {
  const double rho2 = ((r - 124.5) * (r - 124.5) + (c - 124.5) * (c - 124.5)) / (216.0 * 216.0);
  return 500.0 / ((1 + rho2) * (1 + rho2));
}

recon::FixedPattern measure(Die& die, int frames, bool flats = true) {
  recon::FixedPatternBuilder b;
  for (int i = 0; i < frames; ++i) {
    const auto d = die.frame([](int, int) { return 0.0; });
    b.add_dark(die.view(d));
    if (!flats) continue;
    const auto f = die.frame(shaded);
    b.add_flat(die.view(f));
  }
  return b.build();
}

bool used(int r, int c) {
  return r >= 1 && r < kSide - 1 && c < kSide - 1;
}

TEST(FixedPattern, MapsComeBackWithinTheErrorTheyReport) {
  Die die;
  const recon::FixedPattern p = measure(die, 64);
  // Reported: the spread of what the maps hold and their own standard error.
  EXPECT_NEAR(p.dsnu_dn, kDsnu, 0.2);
  EXPECT_NEAR(p.prnu, kPrnu, 0.002);
  EXPECT_NEAR(p.dark_se_dn, kReadNoise / 8, 0.03);  // sqrt(64) = 8
  EXPECT_GT(p.gain_se, 0.001);
  EXPECT_LT(p.gain_se, 0.004);
  // And held: the maps' errors against the die are what they say (rms within 15 % of the se).
  double dark2 = 0, gain2 = 0;
  int n = 0;
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c) {
      const auto k = static_cast<std::size_t>(r * kSide + c);
      if (!used(r, c) || (r == 100 && c == 100) || (r == 150 && c == 50)) continue;
      dark2 += std::pow(p.dark[k] - die.offset[k], 2);
      // The gain is relative to the neighbourhood: its true value is the die's over the local mean (~1).
      gain2 += std::pow(p.gain[k] - die.gain[k], 2);
      ++n;
    }
  EXPECT_NEAR(std::sqrt(dark2 / n) / p.dark_se_dn, 1.0, 0.15);
  // The neighbourhood's median carries its own error (PRNU / sqrt(80) x ~1.25 = 0.28 %): bound wider.
  EXPECT_LT(std::sqrt(gain2 / n), p.gain_se + 0.004);
}

TEST(FixedPattern, RemovedItLeavesTheTemporalNoiseAlone) {
  Die die;
  const recon::FixedPattern p = measure(die, 64);
  // A scene with texture: the corrected frame against the same light on a die with no pattern.
  auto scene = [](int r, int c) { return 250 + 150 * std::sin(0.21 * r) * std::cos(0.17 * c); };
  const auto raw = die.frame(scene, false);
  std::vector<std::uint16_t> fixed(raw.size());
  recon::remove_fixed_pattern(p, die.view(raw), fixed.data());
  double before2 = 0, after2 = 0;
  int n = 0;
  for (int r = 0; r < kSide; ++r)
    for (int c = 0; c < kSide; ++c) {
      if (!used(r, c) || (r == 100 && c == 100) || (r == 150 && c == 50)) continue;
      const auto k = static_cast<std::size_t>(r * kSide + c);
      const double clean = p.black_dn + scene(r, c);
      before2 += std::pow(raw[k] - clean, 2);
      after2 += std::pow(fixed[k] - clean, 2);
      ++n;
    }
  const double before = std::sqrt(before2 / n), after = std::sqrt(after2 / n);
  // Before: DSNU 3.8 DN and PRNU 2 % of ~260 DN (rms). After, predicted from what the maps report:
  // the dark map's error, the gain's (its own, and the neighbourhood median's: 1.2533 PRNU /
  // sqrt(80) for a median of 80 normals) times the signal's rms, and the rounding (1/12 DN^2).
  const double signal_ms = 250.0 * 250.0 + 150.0 * 150.0 / 4;
  const double median_se = 1.2533 * p.prnu / std::sqrt(80.0);
  const double predicted = std::sqrt(p.dark_se_dn * p.dark_se_dn +
                                     (p.gain_se * p.gain_se + median_se * median_se) * signal_ms + 1.0 / 12);
  EXPECT_GT(before, 5.0);
  std::printf("after %.3f DN, predicted %.3f, before %.2f\n", after, predicted, before);
  EXPECT_NEAR(after / predicted, 1.0, 0.15) << "after " << after << " DN, predicted " << predicted;
  // Defects pass through for the defect test; ignored rows and the padding column are copied.
  EXPECT_EQ(fixed[100 * kSide + 100], 1023);
  EXPECT_EQ(fixed[0], raw[0]);
  EXPECT_EQ(fixed[5 * kSide + kSide - 1], raw[5 * kSide + kSide - 1]);
}

TEST(FixedPattern, ShadingStaysInTheImage) {
  Die die;
  die.gain.assign(die.gain.size(), 1.0);  // no PRNU: any gain away from 1 came from the shading
  const recon::FixedPattern p = measure(die, 32);
  // The shading (~500 DN at the centre, ~300 at the corners) would show as gains away from 1 where
  // it curves most: mean gain over each corner's 30 x 30 block and the centre's within 0.1 %
  // (the median's curvature bias, ~0.06 % at the corners; the blocks' noise ~0.01 %).
  auto block_mean = [&](int r0, int c0) {
    double sum = 0;
    for (int r = r0; r < r0 + 30; ++r)
      for (int c = c0; c < c0 + 30; ++c) sum += p.gain[static_cast<std::size_t>(r * kSide + c)];
    return sum / 900;
  };
  for (auto [r0, c0] : {std::pair{1, 0}, {1, 219}, {219, 0}, {219, 219}, {110, 110}})
    EXPECT_NEAR(block_mean(r0, c0), 1.0, 0.001) << "block at " << r0 << ", " << c0;
  // What the gain map holds is its own noise, not a pattern.
  EXPECT_LT(p.prnu, 1.5 * p.gain_se);
}

TEST(FixedPattern, BayerGainsAreAgainstTheSameColour) {
  Die die;
  die.bayer = true;
  // Channel gains as a white target gives them: G 1, R 0.6, B 0.8 (GRBG: row 0 G R, row 1 B G).
  auto colour = [](int r, int c) {
    const double k = (r & 1) == 0 ? ((c & 1) == 0 ? 1.0 : 0.6) : ((c & 1) == 0 ? 0.8 : 1.0);
    return k * shaded(r, c);
  };
  recon::FixedPatternBuilder b;
  for (int i = 0; i < 32; ++i) {
    const auto d = die.frame([](int, int) { return 0.0; });
    b.add_dark(die.view(d));
    const auto f = die.frame(colour);
    b.add_flat(die.view(f));
  }
  const recon::FixedPattern p = b.build();
  EXPECT_NEAR(p.prnu, kPrnu, 0.003);  // not the channels' 0.6-1.0 spread
}

TEST(FixedPattern, RefusesWhatItCannotMeasure) {
  Die die;
  auto expect_refusal = [](auto&& f, const char* says) {
    try {
      f();
      ADD_FAILURE() << "no refusal; expected: " << says;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  expect_refusal([&] { measure(die, 8); }, "dark frames, need at least 16");
  // Flats of a uniform light `dn` above dark: 40 DN is too dim, 990 too near the top.
  auto flats_at = [&](double dn) {
    recon::FixedPatternBuilder b;
    for (int i = 0; i < 16; ++i) {
      const auto d = die.frame([](int, int) { return 0.0; });
      b.add_dark(die.view(d));
      const auto f = die.frame([dn](int, int) { return dn; });
      b.add_flat(die.view(f));
    }
    b.build();
  };
  expect_refusal([&] { flats_at(40.0); }, "more light");
  expect_refusal([&] { flats_at(990.0); }, "less light");
  expect_refusal(
      [&] {
        recon::FixedPatternBuilder b;
        const auto d = die.frame([](int, int) { return 0.0; });
        b.add_dark(die.view(d));
        recon::RawImageView small = die.view(d);
        small.width = small.stride = 100;
        small.height = 100;
        b.add_dark(small);
      },
      "another size");
  // Offsets only (no flats) is a pattern; a frame of another size against it is refused.
  const recon::FixedPattern offsets = measure(die, 16, false);
  EXPECT_TRUE(offsets.gain.empty());
  std::vector<std::uint16_t> small(100 * 100, 100), out(small.size());
  recon::RawImageView v;
  v.data = small.data();
  v.width = v.height = v.stride = 100;
  expect_refusal([&] { recon::remove_fixed_pattern(offsets, v, out.data()); }, "against a pattern of 250");
}

TEST(FixedPatternFile, RoundTripsAndNamesWhatIsWrong) {
  Die die;
  const recon::StereoFixedPattern p{measure(die, 16), measure(die, 16, false)};
  const auto dir = std::filesystem::temp_directory_path() / ("naneye-fp-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "fixed-pattern.yml.gz";
  recon::save_fixed_pattern(file, p);
  const recon::StereoFixedPattern q = recon::load_fixed_pattern(file);
  EXPECT_EQ(q.left.dark, p.left.dark);
  EXPECT_EQ(q.left.gain, p.left.gain);
  EXPECT_EQ(q.right.dark, p.right.dark);
  EXPECT_TRUE(q.right.gain.empty());
  EXPECT_EQ(q.left.black_dn, p.left.black_dn);
  EXPECT_EQ(q.left.dark_frames, 16);
  EXPECT_DOUBLE_EQ(q.left.prnu, p.left.prnu);

  auto refused = [&](const std::string& text, const char* says) {
    const auto bad = dir / "bad.yml";
    std::ofstream(bad) << text;
    try {
      recon::load_fixed_pattern(bad);
      ADD_FAILURE() << "loaded: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.yml"), std::string::npos) << e.what();
    }
  };
  refused("%YAML:1.0\nfoo: 1\n", "not a naneye fixed-pattern file");
  refused("%YAML:1.0\nnaneye_fixed_pattern: 1\nleft: {width: 2, height: 2}\n", "no 'dark' map");
  refused("not yaml at all: [", "fixed-pattern");
  EXPECT_THROW(recon::load_fixed_pattern(dir / "missing.yml"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace naneye::fixed_pattern_test
