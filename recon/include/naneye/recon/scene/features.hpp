#pragma once
// Corner features for scene reconstruction (docs/scene.md): the Shi-Tomasi score (smallest
// eigenvalue of the structure tensor, Shi & Tomasi, CVPR 1994) over the matcher's own window, one
// feature per grid cell so that they spread over the image, kept only where the match they start
// can reach a stated precision given the image's measured noise.
#include <array>
#include <cstdint>
#include <vector>

namespace naneye::recon::scene {

// A float image, row-major, stride = width (the luminance of one eye).
struct GrayView {
  const float* data = nullptr;
  int width = 0, height = 0;
  float at(int c, int r) const { return data[r * width + c]; }
};

struct FeatureSettings {
  int cell_px = 7;        // px; one feature per cell of cell_px x cell_px: 1296 cells on 250 x 250
  int window_radius = 4;  // px; the structure tensor's window, the same as the sub-pixel matcher's
  // px; a feature is kept when the shift sigma its window allows, sqrt(2 sigma_n^2 / lambda_min) (the
  // Cramer-Rao bound of a translation from two images of noise sigma_n), is below this.
  double max_shift_sigma_px = 0.15;
};

struct Feature {
  int u = 0, v = 0;   // left raw pixel (a pixel centre)
  float min_eig = 0;  // lambda_min of the structure tensor (DN^2)
};

// Standard deviation (DN) of white noise in an image, from the absolute response to the 3x3 mask
// [1 -2 1; -2 4 -2; 1 -2 1], which cancels any locally quadratic signal (Immerkaer, "Fast noise
// variance estimation", CVIU 64(2), 1996, Eq. 6). Over the pixels where `mask` (if given) is non-zero:
// the caller marks the pixels whose whole 3x3 neighbourhood is usable (once per camera, not per
// frame). Texture leaks in, so it errs high: a conservative floor. `noise_kernel` (3x3, row-major):
// the image's noise is white noise filtered by it (a Bayer luminance: raw_to_luminance's binomial,
// LkSettings::binomial3), so the mask sees sigma_w |N * k| of it where a pixel holds sigma_w |k|:
// the estimate is sqrt(pi / 2) mean|I * N| |k| / |N * k| (|N| = 6 for white noise, Eq. 6; 1 for
// the binomial, whose white-noise reading is 1/6 of the luminance's noise).
double estimate_noise_sigma(const GrayView& img, const std::uint8_t* mask,
                            const std::array<float, 9>& noise_kernel = {0, 0, 0, 0, 1, 0, 0, 0, 0});

// Reusable: pre-sized buffers for one image size, nothing allocated per frame.
class FeatureDetector {
 public:
  FeatureDetector(int width, int height, const FeatureSettings& s);
  // `usable`: non-zero where a whole matching window around the pixel lies inside the camera's
  // model domain and the active image. Writes at most out.capacity() features (strongest first per
  // cell, cells in raster order).
  void detect(const GrayView& img, const std::uint8_t* usable, double noise_sigma, std::vector<Feature>& out);
  const FeatureSettings& settings() const { return s_; }
  // The smallest lambda_min (DN^2) a feature needs at this noise: the gate of max_shift_sigma_px.
  double min_eig_needed(double noise_sigma) const;
  // lambda_min of the structure tensor over the window at a pixel of the last image; -1 where the
  // window leaves the image.
  float min_eig_at(int u, int v) const;
  // The last image's central-difference gradients (the sub-pixel matcher's template gradients).
  const float* gx() const { return gx_.data(); }
  const float* gy() const { return gy_.data(); }

 private:
  double window_min_eig(int u, int v) const;  // the window inside the image

  FeatureSettings s_;
  int w_, h_;
  std::vector<float> gx_, gy_;
  std::vector<double> ixx_, ixy_, iyy_;  // integral images, (w + 1) x (h + 1)
};

}  // namespace naneye::recon::scene
