#pragma once
// The sensor's fixed pattern, one eye at a time (docs/sensor-calibration.md): the per-pixel dark
// level (black level, column FPN and DSNU: EMVA 1288 sec. 8.2, "dark signal non-uniformity") from
// frames with the lens capped, and the per-pixel gain (PRNU, sec. 8.3) from frames of a uniform white
// target. Both are fixed per die from frame to frame (../shared/notes/measurements.md: DSNU
// 3.5-4.0 DN, PRNU 1-4 %, column FPN 0.5-0.6 DN on the real NanEye), so to a matcher they are noise
// the two eyes do not share that no window averages away; removed once, before reconstruction.
// Pure: frames in, maps out; the file format is in fixed_pattern_io.hpp.
#include <cstdint>
#include <string>
#include <vector>

#include "naneye/recon/corners/detector.hpp"

namespace naneye::recon {

struct FixedPatternSettings {
  // Frames averaged per map. The dark map's own error is the temporal noise / sqrt(n) (read noise
  // 2.5 DN: 0.31 DN at 64); the gain's is the flat's shot noise / sqrt(n) relative to its signal
  // (~8 DN on 500 DN: 0.2 % at 64, against a PRNU of 1-4 %). Below min_* the maps would add more
  // noise than they remove.
  int min_dark_frames = 16;
  int min_flat_frames = 16;
  // px: the flat's local level is the mean of the same-colour pixels within this radius, so the gain
  // keeps only what differs from pixel to pixel (PRNU) and leaves the smooth shading (vignetting and
  // the LED: a factor ~2 over 100 px, docs/simulator.md) in the image, where the matchers expect it.
  int gain_radius_px = 4;
  // DN above the dark level: a flat dimmer than this leaves the gain to the noise (shot + read noise
  // over 16 frames is ~0.5 % of 100 DN); one brighter than white_dn - this is too near saturation.
  double min_flat_signal_dn = 100.0;
  double saturation_margin_dn = 60.0;
  double white_dn = 1023.0;  // the 10-bit scale's top (driver::kPixelMax)
  // DN: the dark map's robust spread above which the "dark" frames saw light (a capped NanEye's
  // DSNU is 3.5-4 DN; a lit scene's texture spreads tens to hundreds): refused, not stored.
  double max_dark_spread_dn = 20.0;
  // Gains outside this range are defects, not PRNU: left at 1 for the defect test downstream
  // (raw_to_luminance) to find, rather than scaled into plausible values.
  double min_gain = 0.5, max_gain = 2.0;

  // Empty when usable, else what is wrong.
  std::string validate() const;
};

// One eye: a raw value v becomes (v - dark) / gain + black_dn, so the corrected frame keeps the
// black level the rest of the pipeline knows; rows and columns the pipeline ignores (reference
// pixels, padding) are copied as they are.
struct FixedPattern {
  int width = 0, height = 0;
  std::vector<float> dark;  // DN, per pixel
  std::vector<float> gain;  // relative to the neighbourhood; empty: offsets only (no flat frames)
  float black_dn = 0;       // the dark map's median
  int dark_frames = 0, flat_frames = 0;
  // The maps' own uncertainty, from the frames' temporal spread: rms over the pixels of the
  // per-pixel standard error (DN; and relative, for the gain).
  double dark_se_dn = 0, gain_se = 0;
  // What the maps hold, to report: the robust sd (1.4826 MAD, blind to the few defects) over the
  // pixels of the dark map (DSNU + column FPN, DN) and of the gain (PRNU, relative).
  double dsnu_dn = 0, prnu = 0;
  bool empty() const { return dark.empty(); }
};

// Accumulates frames of one eye (allocates on the first frame only), then builds its pattern.
class FixedPatternBuilder {
 public:
  explicit FixedPatternBuilder(const FixedPatternSettings& s = {});
  void add_dark(const RawImageView& frame);
  void add_flat(const RawImageView& frame);
  int dark_frames() const { return dark_n_; }
  int flat_frames() const { return flat_n_; }
  // Throws std::invalid_argument saying why (too few frames, frames of another size or layout, a
  // flat too dim or too bright). Flat frames are optional: without them, offsets only.
  FixedPattern build() const;

 private:
  void check_shape(const RawImageView& frame);
  void accumulate(const RawImageView& frame, std::vector<double>& sum, std::vector<double>& sq);
  FixedPatternSettings s_;
  // The first frame's geometry (width 0 before it; no data): every later frame must match it.
  RawImageView shape_{nullptr, 0, 0, 0};
  int dark_n_ = 0, flat_n_ = 0;
  std::vector<double> dark_sum_, dark_sq_, flat_sum_, flat_sq_;
};

// out: in.width x in.height, stride = width. Frames of another size than the pattern's throw
// std::invalid_argument. Saturated pixels stay saturated (a clipped value has no level to correct).
void remove_fixed_pattern(const FixedPattern& pattern, const RawImageView& in, std::uint16_t* out);
// The same into `buffer` (sized on first use), and the view of it: `in` with its data there.
RawImageView remove_fixed_pattern(const FixedPattern& pattern, const RawImageView& in,
                                  std::vector<std::uint16_t>& buffer);

}  // namespace naneye::recon
