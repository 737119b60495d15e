#pragma once
// The frames a user takes to calibrate the sensor's fixed pattern (docs/sensor-calibration.md),
// through the same SensorModel, hence the same die, as every other render: the lens capped (no
// light) and a uniform white target filling the view (shaded like any render: cos^4 of the ray's
// angle, the light a factor ~0.6 dimmer at the corners).
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "naneye/recon/camera/fixed_pattern_io.hpp"
#include "naneye/sim/sensor_model.hpp"

namespace naneye::sim {

// level: the target's light in units of white (0 = dark frame). out: CV_16UC1 250 x 250.
void expose_calibration_frame(const SensorModel& model, int eye, double level, Rng& rng,
                              SensorModel::Scratch& scratch, cv::Mat& out);

// `frames` dark and `frames` flat frames per eye at `level`, built into both eyes' patterns.
recon::StereoFixedPattern measure_fixed_pattern(const SensorSettings& sensor, int frames, double level,
                                                std::uint64_t seed,
                                                const recon::FixedPatternSettings& settings = {});

// Both views pointed at copies with the pattern removed (buffers sized on first use); left as they
// are when `pattern` is empty. For the benches and tests; naneyed's step is app::FixedPatternStep.
void remove_fixed_pattern(const recon::StereoFixedPattern& pattern, recon::RawImageView& left,
                          recon::RawImageView& right, std::vector<std::uint16_t>& left_buffer,
                          std::vector<std::uint16_t>& right_buffer);

}  // namespace naneye::sim
