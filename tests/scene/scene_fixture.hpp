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

// The sensor of the shared renders: the simulator's default, mono or GRBG.
inline sim::SensorSettings textured_sensor(bool bayer) {
  sim::SensorSettings s;
  s.bayer = bayer;
  return s;
}

inline const sim::TexturedRenderer& textured_renderer(bool bayer) {
  static const sim::TexturedRenderer mono(paper_d3(), textured_sensor(false));
  static const sim::TexturedRenderer colour(paper_d3(), textured_sensor(true));
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

}  // namespace naneye::test
