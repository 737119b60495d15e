#include "naneye/app/fixed_pattern_step.hpp"

#include <cstdio>
#include <stdexcept>

namespace naneye::app {

FixedPatternStep::FixedPatternStep(const std::filesystem::path& file, int width, int height)
    : pattern_(recon::load_fixed_pattern(file)) {
  if (pattern_.left.width != width || pattern_.left.height != height)
    throw std::runtime_error(file.string() + ": maps of " + std::to_string(pattern_.left.width) + " x " +
                             std::to_string(pattern_.left.height) + " pixels, frames of " +
                             std::to_string(width) + " x " + std::to_string(height));
  for (auto& b : buffer_) b.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  char text[160];
  const recon::FixedPattern &l = pattern_.left, &r = pattern_.right;
  if (l.gain.empty())
    std::snprintf(text, sizeof text, ": DSNU %.1f / %.1f DN, offsets only)", l.dsnu_dn, r.dsnu_dn);
  else
    std::snprintf(text, sizeof text, ": DSNU %.1f / %.1f DN, PRNU %.1f / %.1f %%)", l.dsnu_dn, r.dsnu_dn,
                  100 * l.prnu, 100 * r.prnu);
  description_ = "fixed pattern removed (" + file.filename().string() + text;
}

recon::RawImageView FixedPatternStep::correct(int eye, const recon::RawImageView& frame) {
  return recon::remove_fixed_pattern(eye == 0 ? pattern_.left : pattern_.right, frame,
                                     buffer_[eye == 0 ? 0 : 1]);
}

}  // namespace naneye::app
