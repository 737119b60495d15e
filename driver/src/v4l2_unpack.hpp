#pragma once
// V4L2 image buffers to sensor frames: pure functions, no device.
#include <cstddef>
#include <cstdint>

#include "naneye/driver/frame.hpp"
#include "naneye/driver/v4l2_source.hpp"

namespace naneye::driver::v4l2_detail {

// Copies the 250 x 250 eye whose top-left pixel is (x0, y0) of `image` (row pitch `stride` bytes)
// into `out.pixels`, converted to 10-bit values. `image` must hold the whole eye.
void unpack_eye(const std::uint8_t* image, std::size_t stride, V4l2Format format, int x0, int y0, Frame& out);

// Where each eye sits in a buffer of the layout: eye 0 = left, 1 = right (unused for alternate).
void eye_origin(V4l2Layout layout, int eye, int& x0, int& y0);

}  // namespace naneye::driver::v4l2_detail
