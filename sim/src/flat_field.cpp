#include "naneye/sim/flat_field.hpp"

#include "naneye/driver/wire_format.hpp"
#include "naneye/sim/render.hpp"

namespace naneye::sim {

using driver::kSensorSize;

void expose_calibration_frame(const SensorModel& model, int eye, double level, Rng& rng,
                              SensorModel::Scratch& scratch, cv::Mat& out) {
  // The shading of a pinhole with the NanEye's focal length (~216 px, docs/scene.md) about the
  // centre: cos^4 = (1 + rho^2 / f^2)^-2. Vignetting off (an ideal sensor): uniform.
  constexpr double kFocalPx = 216.0;
  const double c = (kSensorSize - 1) / 2.0;
  cv::Mat light(kSensorSize, kSensorSize, CV_32FC1);
  for (int r = 0; r < kSensorSize; ++r)
    for (int col = 0; col < kSensorSize; ++col) {
      const double rho2 = ((r - c) * (r - c) + (col - c) * (col - c)) / (kFocalPx * kFocalPx);
      const double shade = model.settings().vignetting ? 1.0 / ((1 + rho2) * (1 + rho2)) : 1.0;
      light.at<float>(r, col) = static_cast<float>(level * shade);
    }
  out.create(kSensorSize, kSensorSize, CV_16UC1);
  model.expose(eye, light, rng, scratch, out.ptr<std::uint16_t>());
}

recon::StereoFixedPattern measure_fixed_pattern(const SensorSettings& sensor, int frames, double level,
                                                std::uint64_t seed,
                                                const recon::FixedPatternSettings& settings) {
  const SensorModel model(sensor);
  Rng rng(seed);
  SensorModel::Scratch scratch;
  cv::Mat frame;
  recon::StereoFixedPattern out;
  for (int eye = 0; eye < 2; ++eye) {
    recon::FixedPatternBuilder b(settings);
    for (int i = 0; i < frames; ++i) {
      expose_calibration_frame(model, eye, 0.0, rng, scratch, frame);
      b.add_dark(raw_view(frame, sensor.bayer));
      expose_calibration_frame(model, eye, level, rng, scratch, frame);
      b.add_flat(raw_view(frame, sensor.bayer));
    }
    (eye == 0 ? out.left : out.right) = b.build();
  }
  return out;
}

void remove_fixed_pattern(const recon::StereoFixedPattern& pattern, recon::RawImageView& left,
                          recon::RawImageView& right, std::vector<std::uint16_t>& left_buffer,
                          std::vector<std::uint16_t>& right_buffer) {
  if (pattern.left.empty()) return;
  left = recon::remove_fixed_pattern(pattern.left, left, left_buffer);
  right = recon::remove_fixed_pattern(pattern.right, right, right_buffer);
}

}  // namespace naneye::sim
