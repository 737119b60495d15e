// The device backends' registration hook (called by make_default_registry()): usb:// and v4l2://.
#include "naneye/driver/source_registry.hpp"
#include "naneye/driver/usb_source.hpp"
#include "naneye/driver/v4l2_source.hpp"

namespace naneye::driver {

void register_device_sources(SourceRegistry& registry) {
  registry.add("usb", [](const SourceUri& uri) {
    return make_usb_source(usb_settings_from(uri, parse_usb_uri(uri)), uri.text);
  });
  registry.add("v4l2", [](const SourceUri& uri) {
    return make_v4l2_source(v4l2_settings_from(parse_v4l2_uri(uri)), uri.text);
  });
}

}  // namespace naneye::driver
