// Light on the pixels -> 10-bit values: optical blur, Bayer sites, exposure, shot and read noise,
// quantisation, defects, reference pixels and padding (docs/simulator.md).
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "naneye/driver/frame.hpp"
#include "naneye/sim/sensor_model.hpp"

namespace naneye::sim {
namespace {
using driver::kSensorSize;

bool reserved(int r, int c) {
  return driver::Frame::is_padding(r, c) || (r == 0 && c < 4) ||
         (r == kSensorSize - 1 && c >= kSensorSize - 4);
}
}  // namespace

double SensorSettings::blur_sigma_px() const {
  // Airy core ~ Gaussian of sigma 0.42 lambda N (Zhang, Zerubia, Olivo-Marin, Appl. Opt. 2007).
  const double diffraction = 0.42 * wavelength_um * f_number / pixel_pitch_um;
  return std::hypot(diffraction, defocus_sigma_px);
}

SensorSettings SensorSettings::ideal() {
  SensorSettings s;
  s.noise = false;
  s.blur = false;
  s.vignetting = false;
  s.defect_pixels = 0;
  return s;
}

SensorSettings SensorSettings::measured(bool bayer) {
  SensorSettings s;
  s.bayer = bayer;
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

SensorModel::SensorModel(const SensorSettings& settings) : s_(settings) {
  // Defects belong to the die, not to the frame: fixed positions per sensor from defect_seed.
  for (int eye = 0; eye < 2; ++eye) {
    Rng g(s_.defect_seed + static_cast<std::uint64_t>(eye));
    std::uniform_int_distribution<int> pos(0, kSensorSize - 1), kind(0, 2);
    defects_[eye].clear();
    defect_values_[eye].clear();
    while (static_cast<int>(defects_[eye].size()) < s_.defect_pixels) {
      const int r = pos(g), c = pos(g);
      const int p = r * kSensorSize + c;
      if (reserved(r, c) || std::find(defects_[eye].begin(), defects_[eye].end(), p) != defects_[eye].end())
        continue;
      defects_[eye].push_back(p);
      // Hot (saturated), dead (reads zero) or stuck at mid-scale.
      static constexpr std::uint16_t kValues[] = {driver::kPixelMax, 0, 512};
      defect_values_[eye].push_back(kValues[kind(g)]);
    }
    // Fixed-pattern noise from its own generator (the defects' positions stay what they were).
    fpn_offset_[eye].clear();
    fpn_gain_[eye].clear();
    if (s_.column_fpn_dn > 0 || s_.dsnu_dn > 0 || s_.prnu > 0) {
      Rng f(s_.defect_seed ^ (0x46504eULL + static_cast<std::uint64_t>(eye)));
      std::normal_distribution<double> n01(0.0, 1.0);
      std::vector<double> column(kSensorSize);
      for (auto& c : column) c = s_.column_fpn_dn * n01(f);
      fpn_offset_[eye].resize(static_cast<std::size_t>(kSensorSize) * kSensorSize);
      fpn_gain_[eye].resize(fpn_offset_[eye].size());
      for (int p = 0; p < kSensorSize * kSensorSize; ++p) {
        const auto k = static_cast<std::size_t>(p);
        fpn_offset_[eye][k] =
            static_cast<float>(column[static_cast<std::size_t>(p % kSensorSize)] + s_.dsnu_dn * n01(f));
        fpn_gain_[eye][k] = static_cast<float>(std::max(0.0, 1.0 + s_.prnu * n01(f)));
      }
    }
  }
}

void SensorModel::expose(int e, const cv::Mat& light_in, Rng& rng, Scratch& scratch,
                         std::uint16_t* out) const {
  const cv::Mat* light = &light_in;
  if (s_.blur) {
    const double sigma = s_.blur_sigma_px();
    const int k = 2 * static_cast<int>(std::ceil(3.0 * sigma)) + 1;
    cv::GaussianBlur(light_in, scratch.blurred, cv::Size(k, k), sigma, sigma, cv::BORDER_REPLICATE);
    light = &scratch.blurred;
  }
  if (s_.noise) {
    // One seed from the caller's generator, the per-pixel normals from OpenCV's (fast in every build).
    cv::RNG cv_rng(rng());
    scratch.noise.create(kSensorSize, kSensorSize, CV_32FC1);
    cv_rng.fill(scratch.noise, cv::RNG::NORMAL, 0.0, 1.0);
  }
  const auto& g = s_.channel_gain;
  const bool fpn = !fpn_offset_[e].empty();
  for (int r = 0; r < kSensorSize; ++r) {
    const bool reset = r >= s_.reset_row && r < s_.reset_row + s_.reset_rows;
    const float* in = light->ptr<float>(r);
    const float* n01 = s_.noise ? scratch.noise.ptr<float>(r) : nullptr;
    std::uint16_t* o = out + static_cast<std::size_t>(r) * kSensorSize;
    for (int c = 0; c < kSensorSize; ++c) {
      double gain = 1.0;
      // GRBG: row 0 G R G R ..., row 1 B G B G ...
      if (s_.bayer) gain = (r & 1) == 0 ? ((c & 1) == 0 ? g[1] : g[0]) : ((c & 1) == 0 ? g[2] : g[1]);
      const auto k = static_cast<std::size_t>(r * kSensorSize + c);
      if (fpn) gain *= fpn_gain_[e][k];
      const double signal = std::max(0.0, static_cast<double>(in[c]) * s_.white_dn * gain);
      double dn = s_.black_level_dn + signal;
      if (fpn) dn += fpn_offset_[e][k];
      if (reset) dn -= s_.reset_depth_dn;
      if (s_.noise) {
        // Shot noise: variance signal * gain (e-) -> signal / gain_e_per_dn in DN^2; plus read noise.
        const double sd = std::sqrt(signal / s_.gain_e_per_dn + s_.read_noise_dn * s_.read_noise_dn);
        dn += sd * n01[c];
      }
      o[c] =
          static_cast<std::uint16_t>(std::clamp(std::lround(dn), 0L, static_cast<long>(driver::kPixelMax)));
    }
  }
  for (std::size_t i = 0; i < defects_[e].size(); ++i) out[defects_[e][i]] = defect_values_[e][i];
  if (s_.reference_pixels) {
    for (int c = 0; c < 4; ++c) out[c] = s_.reference_row0[c];
    out[(kSensorSize - 1) * kSensorSize + kSensorSize - 4] = s_.reference_row249[0];
    out[(kSensorSize - 1) * kSensorSize + kSensorSize - 3] = s_.reference_row249[1];
  }
  for (int r = 0; r < kSensorSize; ++r) out[r * kSensorSize + kSensorSize - 1] = s_.padding_value;
  out[(kSensorSize - 1) * kSensorSize + kSensorSize - 2] = s_.padding_value;
}

}  // namespace naneye::sim
