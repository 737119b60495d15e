// The device backends register usb:// and v4l2:// here (their factories call parse_usb_uri /
// parse_v4l2_uri). Until they exist those schemes are refused as unavailable, after their
// parameters have been checked.
#include "naneye/driver/source_registry.hpp"

namespace naneye::driver {

void register_device_sources(SourceRegistry&) {}

}  // namespace naneye::driver
