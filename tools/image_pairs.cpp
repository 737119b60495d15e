#include "image_pairs.hpp"

#include <glob.h>

#include <stdexcept>

#include "naneye/driver/wire_format.hpp"

namespace naneye::tools {
namespace {

std::vector<std::string> expand(const std::vector<std::string>& args, const char* flag) {
  std::vector<std::string> files;
  for (const auto& a : args) {
    if (a.find_first_of("*?[") == std::string::npos) {
      files.push_back(a);  // a plain name: kept even if missing, so its error names it
      continue;
    }
    glob_t g{};
    const int rc = ::glob(a.c_str(), 0, nullptr, &g);  // sorted by name (no GLOB_NOSORT)
    for (std::size_t i = 0; rc == 0 && i < g.gl_pathc; ++i) files.emplace_back(g.gl_pathv[i]);
    globfree(&g);
    if (rc != 0) throw std::invalid_argument(std::string(flag) + ": no file matches '" + a + "'");
  }
  return files;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> image_pairs(const std::vector<std::string>& left,
                                                             const std::vector<std::string>& right) {
  const auto l = expand(left, "--left"), r = expand(right, "--right");
  if (l.size() != r.size() || l.empty())
    throw std::invalid_argument("--left names " + std::to_string(l.size()) + " files and --right " +
                                std::to_string(r.size()) + ": give the same number, at least one");
  std::vector<std::pair<std::string, std::string>> pairs;
  for (std::size_t i = 0; i < l.size(); ++i) pairs.emplace_back(l[i], r[i]);
  return pairs;
}

recon::RawImageView image_view(const driver::Image10& image) {
  recon::RawImageView v;
  v.data = image.pixels.data();
  v.width = v.stride = image.width;
  v.height = image.height;
  v.layout = image.color == driver::ColorMode::bayer_grbg ? recon::PixelLayout::bayer_grbg
                                                          : recon::PixelLayout::mono;
  const bool naneye_frame = image.width == driver::kSensorSize && image.height == driver::kSensorSize;
  if (!naneye_frame) v.ignore_last_cols = v.ignore_edge_rows = 0;
  return v;
}

}  // namespace naneye::tools
