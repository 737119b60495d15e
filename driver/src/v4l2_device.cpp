#include "v4l2_device.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace naneye::driver::v4l2_detail {
namespace {

[[noreturn]] void fail(const std::string& what, int err) {
  throw V4l2Error(what + ": " + std::strerror(err), err);
}

}  // namespace

std::string fourcc_text(std::uint32_t f) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(i)] = static_cast<char>((f >> (8 * i)) & 0xFF);
  return s;
}

bool V4l2Error::device_gone() const {
  return errno_value == ENODEV || errno_value == ENOENT || errno_value == ENXIO;
}

V4l2Format V4l2Device::pick_format(const std::string& path) const {
  std::vector<std::uint32_t> offered;
  for (std::uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(VIDIOC_ENUM_FMT, &d) < 0) break;
    offered.push_back(d.pixelformat);
  }
  // Most bits first: GREY would throw two of the sensor's ten away.
  for (auto f : {V4l2Format::y10, V4l2Format::y16, V4l2Format::sgrbg10, V4l2Format::grey})
    if (std::find(offered.begin(), offered.end(), fourcc(f)) != offered.end()) return f;
  std::string list;
  for (auto f : offered) list += (list.empty() ? "" : ", ") + fourcc_text(f);
  throw V4l2Error(path + ": offers none of Y10, Y16, SGRBG10, GREY (it offers: " +
                      (list.empty() ? "nothing" : list) + ")",
                  EINVAL);
}

int V4l2Device::xioctl(unsigned long request, void* arg) const {
  int r;
  do {
    r = ::ioctl(fd_, request, arg);
  } while (r < 0 && errno == EINTR);
  return r;
}

void V4l2Device::open(const std::string& path, V4l2Layout layout, std::optional<V4l2Format> wanted,
                      int buffer_count) {
  close();
  path_ = path;
  fd_ = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) fail(path + ": open", errno);
  try {
    v4l2_capability cap{};
    if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) fail(path + ": VIDIOC_QUERYCAP", errno);
    card_ = reinterpret_cast<const char*>(cap.card);
    const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) throw V4l2Error(path + ": not a video capture device", EINVAL);
    if (!(caps & V4L2_CAP_STREAMING)) throw V4l2Error(path + ": does not support streaming I/O", EINVAL);

    const V4l2Format format = wanted ? *wanted : pick_format(path);
    format_ = format;
    int width = 0, height = 0;
    layout_size(layout, width, height);
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<std::uint32_t>(width);
    fmt.fmt.pix.height = static_cast<std::uint32_t>(height);
    fmt.fmt.pix.pixelformat = fourcc(format);
    fmt.fmt.pix.field = layout == V4l2Layout::alternate ? V4L2_FIELD_ANY : V4L2_FIELD_NONE;
    if (xioctl(VIDIOC_S_FMT, &fmt) < 0) fail(path + ": VIDIOC_S_FMT", errno);
    if (fmt.fmt.pix.pixelformat != fourcc(format))
      throw V4l2Error(path + ": format " + std::string(to_string(format)) + " refused (device chose " +
                          fourcc_text(fmt.fmt.pix.pixelformat) + ")",
                      EINVAL);
    if (fmt.fmt.pix.width != static_cast<std::uint32_t>(width) ||
        fmt.fmt.pix.height != static_cast<std::uint32_t>(height))
      throw V4l2Error(path + ": layout " + std::string(to_string(layout)) + " needs " +
                          std::to_string(width) + "x" + std::to_string(height) + ", device gives " +
                          std::to_string(fmt.fmt.pix.width) + "x" + std::to_string(fmt.fmt.pix.height),
                      EINVAL);
    stride_ = fmt.fmt.pix.bytesperline
                  ? fmt.fmt.pix.bytesperline
                  : static_cast<std::size_t>(width) * static_cast<std::size_t>(bytes_per_pixel(format));
    if (stride_ < static_cast<std::size_t>(width) * static_cast<std::size_t>(bytes_per_pixel(format)))
      throw V4l2Error(path + ": bytesperline " + std::to_string(stride_) + " too small", EINVAL);
    image_size_ = stride_ * static_cast<std::size_t>(height);

    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(buffer_count);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(VIDIOC_REQBUFS, &req) < 0) fail(path + ": VIDIOC_REQBUFS", errno);
    if (req.count < 2)
      throw V4l2Error(path + ": only " + std::to_string(req.count) + " buffer(s) granted", ENOMEM);
    buffers_.resize(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (xioctl(VIDIOC_QUERYBUF, &b) < 0) fail(path + ": VIDIOC_QUERYBUF", errno);
      if (b.length < image_size_) throw V4l2Error(path + ": buffer smaller than one image", EINVAL);
      void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (p == MAP_FAILED) fail(path + ": mmap", errno);
      buffers_[i] = {p, b.length};
      requeue(static_cast<int>(i));
    }
  } catch (...) {
    close();
    throw;
  }
}

void V4l2Device::stream_on() {
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(VIDIOC_STREAMON, &type) < 0) fail(path_ + ": VIDIOC_STREAMON", errno);
  streaming_ = true;
}

void V4l2Device::requeue(int index) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = static_cast<std::uint32_t>(index);
  if (xioctl(VIDIOC_QBUF, &b) < 0) fail(path_ + ": VIDIOC_QBUF", errno);
}

bool V4l2Device::dequeue(std::chrono::milliseconds timeout, Dequeued& out) {
  pollfd p{fd_, POLLIN, 0};
  const int n = ::poll(&p, 1, static_cast<int>(timeout.count()));
  if (n < 0) {
    if (errno == EINTR) return false;
    fail(path_ + ": poll", errno);
  }
  if (n == 0) return false;
  if (p.revents & (POLLERR | POLLHUP | POLLNVAL)) {
    // A vanished node reports POLLERR; tell it apart from a transient error by asking the device.
    v4l2_capability cap{};
    if (xioctl(VIDIOC_QUERYCAP, &cap) < 0) fail(path_ + ": device gone", errno);
  }
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (xioctl(VIDIOC_DQBUF, &b) < 0) {
    if (errno == EAGAIN) return false;
    fail(path_ + ": VIDIOC_DQBUF", errno);
  }
  out.index = static_cast<int>(b.index);
  out.bytesused = b.bytesused;
  out.timestamp_ns = static_cast<std::int64_t>(b.timestamp.tv_sec) * 1'000'000'000 +
                     static_cast<std::int64_t>(b.timestamp.tv_usec) * 1000;
  out.sequence = b.sequence;
  out.field = b.field;
  out.error = (b.flags & V4L2_BUF_FLAG_ERROR) != 0;
  return true;
}

void V4l2Device::close() {
  if (fd_ < 0) return;
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (auto& m : buffers_)
    if (m.start) ::munmap(m.start, m.length);
  buffers_.clear();
  v4l2_requestbuffers req{};
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  xioctl(VIDIOC_REQBUFS, &req);  // count 0 frees the driver's buffers
  ::close(fd_);
  fd_ = -1;
}

}  // namespace naneye::driver::v4l2_detail
