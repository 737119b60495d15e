#pragma once
// One open V4L2 capture node in mmap streaming mode, through plain open/ioctl/mmap/poll.
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "naneye/driver/v4l2_source.hpp"

namespace naneye::driver::v4l2_detail {

// A V4L2 pixel format's four characters ("Y10 ", "BA10"), for messages and device lists.
std::string fourcc_text(std::uint32_t fourcc);

// errno_value lets callers tell a vanished device (ENODEV, ENOENT, ENXIO) from a real refusal.
class V4l2Error : public std::runtime_error {
 public:
  V4l2Error(const std::string& what, int err) : std::runtime_error(what), errno_value(err) {}
  bool device_gone() const;
  int errno_value;
};

struct Dequeued {
  int index = -1;
  std::size_t bytesused = 0;
  std::int64_t timestamp_ns = 0;
  std::uint32_t sequence = 0;
  std::uint32_t field = 0;
  bool error = false;  // V4L2_BUF_FLAG_ERROR: the driver says the data is damaged
};

class V4l2Device {
 public:
  V4l2Device() = default;
  ~V4l2Device() { close(); }
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;

  // open + QUERYCAP + S_FMT (checked against the layout's size) + REQBUFS/QUERYBUF/mmap + QBUF all.
  // No `format`: the first of Y10, Y16, SGRBG10, GREY that ENUM_FMT lists.
  void open(const std::string& path, V4l2Layout layout, std::optional<V4l2Format> format, int buffer_count);
  V4l2Format format() const { return format_; }
  void stream_on();
  // Waits up to `timeout` for a filled buffer. false on timeout.
  bool dequeue(std::chrono::milliseconds timeout, Dequeued& out);
  void requeue(int index);
  void close();  // STREAMOFF, munmap, close; never throws
  bool is_open() const { return fd_ >= 0; }

  const std::uint8_t* data(int index) const {
    return static_cast<const std::uint8_t*>(buffers_[static_cast<std::size_t>(index)].start);
  }
  std::size_t stride() const { return stride_; }
  std::size_t image_size() const { return image_size_; }
  const std::string& card() const { return card_; }

 private:
  struct Mapping {
    void* start = nullptr;
    std::size_t length = 0;
  };
  int xioctl(unsigned long request, void* arg) const;
  V4l2Format pick_format(const std::string& path) const;

  int fd_ = -1;
  bool streaming_ = false;
  std::string path_, card_;
  std::vector<Mapping> buffers_;
  std::size_t stride_ = 0, image_size_ = 0;
  V4l2Format format_ = V4l2Format::y10;
};

}  // namespace naneye::driver::v4l2_detail
