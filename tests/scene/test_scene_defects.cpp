// raw_to_luminance's defect test on textured scenes (`textured` = true, the scene path's luminance):
// real defects are still repaired, the texture is not. Seen through this lens (blur ~0.4 px) the
// presets' texture makes isolated extremes among a Bayer site's neighbours, 2 px away, which the
// board's rule (beyond all same-site neighbours by 60 DN) took for defects.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <utility>
#include <vector>

#include "naneye/recon/corners/detector.hpp"
#include "scene_fixture.hpp"

namespace naneye {
namespace {

struct Repairs {
  int defects_repaired = 0;  // of the pixels made defects
  int texture_changed = 0;   // other mosaic pixels the test replaced
};

// The mosaic after the defect pass (raw_to_luminance leaves it in `scratch` for Bayer frames).
Repairs run(const std::vector<std::uint16_t>& raw, const std::vector<std::pair<int, int>>& defects,
            bool textured) {
  constexpr int n = 250;
  recon::RawImageView v{raw.data(), n, n, n, recon::PixelLayout::bayer_grbg, 1, 1};
  std::vector<float> out(n * n), scratch(n * n);
  recon::raw_to_luminance(v, out.data(), scratch.data(), recon::kDefectThresholdDn, 0, -1, nullptr, textured);
  Repairs r;
  std::vector<char> is_defect(n * n, 0);
  for (const auto& [row, col] : defects) {
    const auto i = static_cast<std::size_t>(row * n + col);
    is_defect[i] = 1;
    r.defects_repaired += scratch[i] != static_cast<float>(raw[i]);
  }
  for (int row = 2; row < n - 2; ++row)
    for (int col = 2; col < n - 3; ++col) {
      const auto i = static_cast<std::size_t>(row * n + col);
      r.texture_changed += !is_defect[i] && scratch[i] != static_cast<float>(raw[i]);
    }
  return r;
}

TEST(SceneDefects, TheTextureIsKeptAndHotDeadAndStuckPixelsAreStillRepaired) {
  for (const char* name : {"plane", "sphere", "height"}) {
    const auto& p = test::textured_pair(name, true);
    std::vector<std::uint16_t> raw(p.left.begin<std::uint16_t>(), p.left.end<std::uint16_t>());
    // 30 defects of the three kinds the datasheet names, where the surface is lit (the sensor's own
    // defects are anywhere, but in the unlit corners any rule repairs them).
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> pos(20, 229);
    std::vector<std::pair<int, int>> defects;
    int kind = 0;
    while (defects.size() < 30) {
      const int row = pos(rng), col = pos(rng);
      const auto i = static_cast<std::size_t>(row * 250 + col);
      if (raw[i] < 150) continue;
      static constexpr std::array<std::uint16_t, 3> kValues{1023, 0, 512};  // hot, dead, stuck mid-scale
      if (kValues[kind] == 512 && raw[i] > 380) continue;  // stuck near its own level: no defect
      raw[i] = kValues[kind];
      kind = (kind + 1) % 3;
      defects.emplace_back(row, col);
    }
    const Repairs board = run(raw, defects, false), scene = run(raw, defects, true);
    std::printf(
        "%-7s board rule: %d/30 defects repaired, %d texture pixels replaced; scene rule: %d/30, %d\n", name,
        board.defects_repaired, board.texture_changed, scene.defects_repaired, scene.texture_changed);
    // As many planted defects as the board rule repairs (it misses a dead or stuck pixel whose
    // neighbours are as dark or as bright), and an order of magnitude fewer texture pixels taken.
    EXPECT_GE(scene.defects_repaired, board.defects_repaired - 2) << name;
    EXPECT_GT(board.texture_changed, 150) << name;
    EXPECT_LT(scene.texture_changed, board.texture_changed / 10) << name;
  }
}

}  // namespace
}  // namespace naneye
