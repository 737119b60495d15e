#pragma once
// The imaging-condition matrix (docs/corners.md, "Across imaging conditions"): the
// simulator's sensor and scene changed one way at a time from a sensor close to the measured real
// NanEye (/work/shared/notes/measurements.md: blur ~1 px, shot-noise slope 0.14 DN per electron,
// read noise 2.5 DN, column FPN 0.55 DN, DSNU 3.8 DN, PRNU 2 %, a reset line of 3 rows at -16 DN).
// Shared by tests/corners/test_conditions.cpp (a few pairs each) and bench/bench_conditions.cpp.
#include <string>
#include <vector>

#include "naneye/sim/scene.hpp"
#include "naneye/sim/sensor.hpp"

namespace naneye::test {

struct ImagingCondition {
  std::string name;
  sim::SceneSettings scene;
  sim::SensorSettings sensor;
};

// The real sensor's figures (ranges' middles), mono or GRBG.
inline sim::SensorSettings real_sensor(bool bayer) {
  sim::SensorSettings s;
  s.bayer = bayer;
  s.channel_gain = {1.0, 1.0, 1.0};
  s.gain_e_per_dn = 1.0 / 0.14;
  s.read_noise_dn = 2.5;
  s.defocus_sigma_px = 0.98;  // with the f/2.7 diffraction (0.21 px): sigma 1.0 px
  s.column_fpn_dn = 0.55;
  s.dsnu_dn = 3.8;
  s.prnu = 0.02;
  s.reset_rows = 3;
  s.reset_row = 200;
  s.reset_depth_dn = 16.0;
  return s;
}

inline std::vector<ImagingCondition> imaging_conditions() {
  std::vector<ImagingCondition> out;
  auto add = [&](const std::string& name, auto&& change, bool bayer = false) {
    ImagingCondition c{name, sim::SceneSettings{}, real_sensor(bayer)};
    change(c);
    out.push_back(c);
  };
  auto none = [](ImagingCondition&) {};
  add("simulator default (bench_corners' sensor)",
      [](ImagingCondition& c) { c.sensor = sim::SensorSettings{}; });
  add("real sensor, mono", none);
  add("real sensor, Bayer, gains R/G/B 1.0/1.0/1.0", none, true);
  add(
      "real sensor, Bayer, gains R/G/B 1.5/1.0/0.5",
      [](ImagingCondition& c) {
        c.sensor.channel_gain = {1.5, 1.0, 0.5};
      },
      true);
  add(
      "real sensor, Bayer, gains R/G/B 0.5/0.8/1.4",
      [](ImagingCondition& c) {
        c.sensor.channel_gain = {0.5, 0.8, 1.4};
      },
      true);
  add("dim: white squares ~200 DN", [](ImagingCondition& c) { c.sensor.white_dn = 200; });
  add("bright: whites clipped", [](ImagingCondition& c) { c.sensor.white_dn = 1300; });
  add("blur sigma 1.5 px", [](ImagingCondition& c) { c.sensor.defocus_sigma_px = 1.485; });
  add("grey background, no white margin", [](ImagingCondition& c) {
    c.scene.border_squares = 0.0;
    c.scene.background = 0.5;
  });
  add("low-contrast print (black 45 % of white)", [](ImagingCondition& c) { c.scene.black = 0.45; });
  add("4x the shot-noise variance", [](ImagingCondition& c) { c.sensor.gain_e_per_dn /= 4.0; });
  return out;
}

}  // namespace naneye::test
