#pragma once
// A rectified stereo pair made exactly: one constant disparity, a band-limited texture written as a
// sum of sinusoids, so that either eye samples it exactly at any sub-pixel shift (no resampling of
// the input, which would itself correlate and shape the noise). What the rectified matcher
// (recon/scene/dense_match.hpp) does with it is the matcher's own doing: its window model, its
// reference field, its noise estimate; not the camera model or a surface's shape
// (bench_dense_snr, tests/scene/test_dense_snr.cpp).
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace naneye::sim {

struct WaveTexture {
  struct Wave {
    double fx, fy, amp, phase;  // cycles/px, cycles/px, DN, rad
  };
  std::vector<Wave> waves;
};

// 300 sinusoids of uniformly random direction and of frequency uniform over the disc of radius
// 0.35 cycles/px (below Nyquist with room for the blur's tail), amplitudes normal and shaped by a
// Gaussian blur of blur_px (its transfer function exp(-2 pi^2 f^2 blur^2)), scaled to a standard
// deviation of contrast_dn.
WaveTexture make_wave_texture(double blur_px, double contrast_dn, std::uint64_t seed);

// CV_32FC1 width x height: mean_dn + the texture at (x + shift_px, y). The left eye of a pair at
// disparity d (d = u_left - u_right) is shift 0, the right one shift d.
cv::Mat render_waves(const WaveTexture& t, int width, int height, double mean_dn, double shift_px);

}  // namespace naneye::sim
