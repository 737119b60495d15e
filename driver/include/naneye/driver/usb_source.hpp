#pragma once
// usb://: the libusb transport (usb_transport.hpp) feeding the stream parser, pairer and hand-over of
// ByteStreamSource. Bytes are fed on the transport's event thread in arrival order; a lost board
// cuts the record in flight (counted) and the source waits for it to come back.
#include <filesystem>
#include <memory>
#include <string>

#include "naneye/driver/byte_stream_source.hpp"
#include "naneye/driver/source_uri.hpp"
#include "naneye/driver/usb_transport.hpp"

namespace naneye::driver {

struct UsbSourceSettings {
  UsbTransportSettings transport;
  StreamSettings stream;
};

// The profile for the URI's VID:PID from `profile_dir` (else the built-in one for the spec's ids,
// else a generic one), with the URI's serial, interface and endpoint applied on top.
UsbSourceSettings usb_settings_from(const SourceUri& uri, const UsbUri& parsed,
                                    const std::filesystem::path& profile_dir = default_profile_dir());

std::unique_ptr<FrameSource> make_usb_source(UsbSourceSettings settings, std::string uri = {});

}  // namespace naneye::driver
