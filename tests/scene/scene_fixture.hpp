#pragma once
// Rendered textured scenes shared by the scene tests (one Renderer per sensor, one render per scene).
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <utility>

#include "../support/paper_rig.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::test {

// Every textured preset (sim/src/textured_surface.cpp), mono and Bayer: the cases of the sparse and
// dense tests against truth.
inline auto every_preset() {
  return ::testing::Combine(::testing::Values("plane", "plane-far", "sphere", "tube", "height"),
                            ::testing::Bool());
}
inline std::string preset_case_name(const ::testing::TestParamInfo<std::tuple<std::string, bool>>& info) {
  std::string n = std::get<0>(info.param);
  for (auto& c : n)
    if (c == '-') c = '_';
  return n + (std::get<1>(info.param) ? "_bayer" : "_mono");
}

inline const sim::TexturedRenderer& textured_renderer(bool bayer) {
  static const sim::TexturedRenderer mono(paper_d3(), sim::SensorSettings{});
  static const sim::TexturedRenderer colour(paper_d3(), [] {
    sim::SensorSettings s;
    s.bayer = true;
    return s;
  }());
  return bayer ? colour : mono;
}

inline const sim::TexturedPair& textured_pair(const std::string& preset, bool bayer, std::uint64_t seed = 5) {
  static std::map<std::tuple<std::string, bool, std::uint64_t>, sim::TexturedPair> cache;
  const auto key = std::make_tuple(preset, bayer, seed);
  auto it = cache.find(key);
  if (it == cache.end()) {
    sim::Rng rng(seed);
    it = cache.emplace(key, textured_renderer(bayer).render(*sim::textured_preset(preset), rng)).first;
  }
  return it->second;
}

// bench_scene's k-th render of a preset (k = 0, 1, 2): the texture seed moved by 100 k, the noise
// seeded 1000 + k, so that a test's figures can be set beside the benchmark's.
inline sim::TexturedPair bench_render(const sim::TexturedRenderer& renderer, const std::string& preset,
                                      int k) {
  sim::TexturedSceneSettings scene = *sim::textured_preset(preset);
  scene.texture.seed += static_cast<std::uint64_t>(100 * k);
  sim::Rng rng(1000 + static_cast<std::uint64_t>(k));
  return renderer.render(scene, rng);
}

}  // namespace naneye::test
