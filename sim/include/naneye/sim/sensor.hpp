#pragma once
// The NanEye 2D sensor and lens as the simulator models them (docs/simulator.md gives the sources
// of each figure: the spec/datasheet where it states one, otherwise an assumption, named as such).
#include <array>
#include <cstdint>

namespace naneye::sim {

struct SensorSettings {
  bool bayer = false;  // GRBG colour variant (row 0: G R G R ..., row 1: B G B G ...) or monochrome
  // Relative sensitivities of the R, G, B sites to the white light (colour variant only).
  std::array<double, 3> channel_gain{0.78, 1.0, 0.62};

  // Exposure: a white square facing the camera on axis at the light's reference distance gives
  // black_level_dn + white_dn (before vignetting).
  double black_level_dn = 48.0;
  double white_dn = 760.0;

  // Noise: shot noise from the electron count (gain_e_per_dn electrons per DN, Poisson approximated
  // by a Gaussian of the same variance) plus read noise.
  bool noise = true;
  double gain_e_per_dn = 12.0;
  double read_noise_dn = 1.8;

  // Optical blur: the F-number's diffraction (Airy core ~ Gaussian, sigma = 0.42 lambda N) in pixels
  // of pixel_pitch_um, combined in quadrature with a defocus sigma.
  bool blur = true;
  double wavelength_um = 0.55;
  double f_number = 2.7;
  double pixel_pitch_um = 3.0;
  double defocus_sigma_px = 0.35;
  double blur_sigma_px() const;

  // Natural cos^4 fall-off of the lens (the light's fall-off is part of SceneSettings::lighting).
  bool vignetting = true;

  // Defect pixels (< 10 per sensor per the datasheet), at positions fixed by defect_seed per sensor.
  int defect_pixels = 5;
  std::uint64_t defect_seed = 0x4e616e457965ULL;

  // Fixed-pattern noise of the die, fixed per sensor by defect_seed like the defects (real NanEye 2D
  // figures: /work/shared/notes/measurements.md; 0 = off, the default, so earlier renders stay):
  // column-to-column offsets (sd, DN), per-pixel offsets (DSNU, sd, DN), per-pixel gain (PRNU, sd).
  double column_fpn_dn = 0.0;
  double dsnu_dn = 0.0;
  double prnu = 0.0;
  // The real sensor's dark "reset line": reset_rows rows from reset_row read reset_depth_dn lower
  // (additive; on hardware rows 168-244, moving with the exposure, -12..-24 DN, 2-3 rows). 0: none.
  int reset_rows = 0;
  int reset_row = 200;
  double reset_depth_dn = 16.0;

  // Reference pixels of the spec: row 0 columns 0..3 and row 249 columns 246, 247. The levels follow
  // the vendor parser's check (row 0: px 0 and 2 <= 600, px 1 and 3 >= 800; row 249: px 246 <= 600,
  // px 247 >= 800); which of each pair is dark is unconfirmed on hardware, hence configurable.
  bool reference_pixels = true;
  std::array<std::uint16_t, 4> reference_row0{40, 1000, 40, 1000};
  std::array<std::uint16_t, 2> reference_row249{40, 1000};  // columns 246, 247
  std::uint16_t padding_value = 0;                          // column 249 and row 249 columns 248-249

  // An ideal sensor: no noise, blur, vignetting or defects; reference pixels and padding kept.
  static SensorSettings ideal();
  // The real NanEye 2D as measured on public frames (the middles of the ranges in
  // /work/shared/notes/measurements.md, "The real sensor"): shot-noise slope 0.14 DN per electron,
  // read noise 2.5 DN, blur sigma 1.0 px, column FPN 0.55 DN, DSNU 3.8 DN, PRNU 2 %, a 3-row reset
  // line 16 DN deep at row 200. The defaults above are ~3x sharper and carry no fixed pattern.
  static SensorSettings measured(bool bayer);
};

}  // namespace naneye::sim
