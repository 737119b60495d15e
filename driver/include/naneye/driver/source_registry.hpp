#pragma once
// SourceRegistry: URI scheme -> factory. No global: whoever opens sources (daemon, CLI, tests) builds
// one with make_default_registry() and may add more schemes (e.g. the simulator's "sim").
//
// Hook for the device backends: register_device_sources() (driver/src/device_sources.cpp) adds
// usb:// and v4l2://; make_default_registry() calls it after registering file:// and images://.
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "naneye/driver/frame_source.hpp"
#include "naneye/driver/source_uri.hpp"

namespace naneye::driver {

// Builds a source from a parsed URI; throws SourceError for bad parameters. Does not start it.
using SourceFactory = std::function<std::unique_ptr<FrameSource>(const SourceUri&)>;

class SourceRegistry {
 public:
  void add(std::string scheme, SourceFactory factory);  // replaces an earlier factory for the scheme
  bool has(std::string_view scheme) const;
  std::vector<std::string> schemes() const;
  // Parses `uri` (a plain path means file://) and calls the scheme's factory. Unknown schemes throw
  // SourceError listing the known ones.
  std::unique_ptr<FrameSource> open(std::string_view uri) const;

 private:
  std::map<std::string, SourceFactory, std::less<>> factories_;
};

void register_file_source(SourceRegistry& registry);
void register_image_source(SourceRegistry& registry);    // images:// (image_source.hpp)
void register_device_sources(SourceRegistry& registry);  // usb, v4l2 (device backends)
SourceRegistry make_default_registry();

}  // namespace naneye::driver
