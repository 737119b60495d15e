#include "naneye/driver/source_registry.hpp"

#include "naneye/driver/image_source.hpp"

namespace naneye::driver {

void SourceRegistry::add(std::string scheme, SourceFactory factory) {
  factories_[std::move(scheme)] = std::move(factory);
}

bool SourceRegistry::has(std::string_view scheme) const {
  return factories_.find(scheme) != factories_.end();
}

std::vector<std::string> SourceRegistry::schemes() const {
  std::vector<std::string> v;
  for (const auto& [k, f] : factories_) v.push_back(k);
  return v;
}

std::unique_ptr<FrameSource> SourceRegistry::open(std::string_view text) const {
  const SourceUri uri = parse_uri(text);
  const auto it = factories_.find(uri.scheme);
  if (it == factories_.end()) {
    // Still check the parameters of schemes we know, so a typo is reported as such.
    if (uri.scheme == "usb") parse_usb_uri(uri);
    if (uri.scheme == "v4l2") parse_v4l2_uri(uri);
    std::string known;
    for (const auto& [k, f] : factories_) known += (known.empty() ? "" : ", ") + k + "://";
    throw SourceError("unknown or unavailable source scheme '" + uri.scheme + "://' in '" + uri.text +
                      "'; available: " + known);
  }
  return it->second(uri);
}

SourceRegistry make_default_registry() {
  SourceRegistry r;
  register_file_source(r);
  register_image_source(r);
  register_device_sources(r);
  return r;
}

}  // namespace naneye::driver
