// raw_to_luminance: defect pixels replaced by the median of their same-site neighbours, nothing else
// touched, mono and Bayer; checked against a plain per-pixel transcription of the rule (no row
// pre-screening) on noisy frames with isolated and adjacent defects.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {
namespace {

constexpr int kW = 250, kH = 250;
constexpr float kThreshold = 60.0f;

// The rule of corners.hpp, pixel by pixel in raster order, replacements visible to later pixels.
void reference_defects(std::vector<float>& f, int step) {
  for (int r = step; r < kH - step; ++r) {
    for (int c = step; c < kW - step; ++c) {
      std::array<float, 8> nb;
      std::size_t k = 0;
      for (int dr = -step; dr <= step; dr += step)
        for (int dc = -step; dc <= step; dc += step)
          if (dr != 0 || dc != 0) nb[k++] = f[static_cast<std::size_t>((r + dr) * kW + c + dc)];
      const float v = f[static_cast<std::size_t>(r * kW + c)];
      const auto [mn, mx] = std::minmax_element(nb.begin(), nb.end());
      if (v > *mx + kThreshold || v < *mn - kThreshold) {
        std::nth_element(nb.begin(), nb.begin() + 4, nb.end());
        f[static_cast<std::size_t>(r * kW + c)] = nb[4];
      }
    }
  }
}

// A smooth ramp with shot-like noise, a sharp vertical edge, and defects: isolated hot and dead
// pixels plus a horizontal and a vertical pair of adjacent hot pixels (neither is beyond the other).
std::vector<std::uint16_t> noisy_frame(std::uint64_t seed, std::vector<std::pair<int, int>>& defects) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, 6.0f);
  std::vector<std::uint16_t> raw(kW * kH);
  for (int r = 0; r < kH; ++r)
    for (int c = 0; c < kW; ++c) {
      const float base = (c < 120 ? 200.0f : 700.0f) + 0.5f * static_cast<float>(r);
      raw[static_cast<std::size_t>(r * kW + c)] =
          static_cast<std::uint16_t>(std::clamp(base + noise(rng), 0.0f, 1023.0f));
    }
  std::uniform_int_distribution<int> pos(5, kW - 6);
  for (int i = 0; i < 40; ++i) {
    const int r = pos(rng), c = pos(rng);
    raw[static_cast<std::size_t>(r * kW + c)] = (i % 2) ? 1023 : 0;
    defects.emplace_back(r, c);
  }
  raw[100 * kW + 60] = raw[100 * kW + 61] = 1023;  // adjacent pair along the row
  raw[150 * kW + 30] = raw[151 * kW + 30] = 1023;  // adjacent pair along the column
  return raw;
}

TEST(Luminance, MonoDefectsMatchThePlainRule) {
  std::vector<std::pair<int, int>> defects;
  const auto raw = noisy_frame(7, defects);
  RawImageView v{raw.data(), kW, kH, kW, PixelLayout::mono, 0, 0};
  std::vector<float> out(kW * kH), scratch(kW * kH);
  raw_to_luminance(v, out.data(), scratch.data(), kThreshold);

  std::vector<float> ref(raw.begin(), raw.end());
  reference_defects(ref, 1);
  int replaced = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    ASSERT_EQ(out[i], ref[i]) << "pixel " << i % kW << "," << i / kW;
    replaced += out[i] != static_cast<float>(raw[i]);
  }
  // Every isolated defect (none sits next to another here, barring a chance hit) is repaired to
  // the local level, the adjacent pairs are left alone (neither pixel is beyond all neighbours).
  int repaired = 0;
  for (const auto& [r, c] : defects) {
    const float level = (c < 120 ? 200.0f : 700.0f) + 0.5f * static_cast<float>(r);
    if (c == 119 || c == 120) continue;  // on the edge: the median is of either side
    repaired += std::abs(out[static_cast<std::size_t>(r * kW + c)] - level) < 30.0f;
  }
  EXPECT_GE(repaired, 36);
  EXPECT_EQ(out[100 * kW + 60], 1023.0f);
  EXPECT_EQ(out[150 * kW + 30], 1023.0f);
  EXPECT_GE(replaced, 36);
  EXPECT_LE(replaced, 44);  // the noise (6 DN, threshold 60) makes no defects of its own
}

TEST(Luminance, BayerDefectsUseTheSameSite) {
  std::vector<std::pair<int, int>> defects;
  const auto raw = noisy_frame(11, defects);
  RawImageView v{raw.data(), kW, kH, kW, PixelLayout::bayer_grbg, 0, 0};
  std::vector<float> out(kW * kH), scratch(kW * kH);
  raw_to_luminance(v, out.data(), scratch.data(), kThreshold);
  // The defect pass runs on the mosaic (same-site neighbours two pixels away), then the binomial.
  std::vector<float> ref(raw.begin(), raw.end());
  reference_defects(ref, 2);
  ASSERT_EQ(scratch.size(), ref.size());
  for (std::size_t i = 0; i < ref.size(); ++i)
    ASSERT_EQ(scratch[i], ref[i]) << "pixel " << i % kW << "," << i / kW;
  // An interior pixel of the output is the 3x3 binomial of the repaired mosaic.
  const int r = 100, c = 61;
  float sum = 0;
  const float k[3] = {1, 2, 1};
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc)
      sum += k[dr + 1] * k[dc + 1] * ref[static_cast<std::size_t>((r + dr) * kW + c + dc)];
  EXPECT_FLOAT_EQ(out[static_cast<std::size_t>(r * kW + c)], sum / 16.0f);
}

}  // namespace
}  // namespace naneye::recon

namespace naneye::recon {
namespace {

// Tracking computes only the board's rows: those equal the whole-image computation (exactly, unless a
// defect pixel sits within two rows outside the band: its repair is then not seen by the band).
TEST(Luminance, RowBandEqualsTheWholeImage) {
  for (const PixelLayout layout : {PixelLayout::mono, PixelLayout::bayer_grbg}) {
    std::vector<std::pair<int, int>> defects;
    const auto raw = noisy_frame(13, defects);
    const RawImageView v{raw.data(), kW, kH, kW, layout, 1, 1};
    std::vector<float> whole(kW * kH), band(kW * kH, -1.0f), scratch(kW * kH);
    raw_to_luminance(v, whole.data(), scratch.data());
    for (const auto& [lo, hi] : {std::pair{0, 40}, std::pair{57, 139}, std::pair{200, 250}}) {
      std::fill(band.begin(), band.end(), -1.0f);
      raw_to_luminance(v, band.data(), scratch.data(), kDefectThresholdDn, lo, hi);
      for (int r = lo; r < hi; ++r)
        for (int c = 0; c < kW; ++c)
          ASSERT_EQ(band[static_cast<std::size_t>(r * kW + c)], whole[static_cast<std::size_t>(r * kW + c)])
              << "row " << r << " col " << c << " band " << lo << "-" << hi;
      // Rows well outside the band are not computed (the work saved).
      if (lo >= 10) {
        EXPECT_EQ(band[static_cast<std::size_t>((lo - 10) * kW + 5)], -1.0f);
      }
    }
  }
}

}  // namespace
}  // namespace naneye::recon
