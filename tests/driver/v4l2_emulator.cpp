#include "v4l2_emulator.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace naneye::test {

V4l2Emulator::V4l2Emulator() {
  testbed_ = umockdev_testbed_new();
  handler_ = umockdev_ioctl_base_new();
  g_signal_connect(handler_, "handle-ioctl", G_CALLBACK(&V4l2Emulator::on_ioctl), this);
}

V4l2Emulator::~V4l2Emulator() {
  for (const auto& n : attached_) umockdev_testbed_detach_ioctl(testbed_, n.c_str(), nullptr);
  g_object_unref(handler_);
  g_object_unref(testbed_);
}

std::uint32_t V4l2Emulator::bytes_per_pixel(std::uint32_t f) {
  return f == V4L2_PIX_FMT_GREY ? 1 : 2;
}

void V4l2Emulator::plug(const V4l2DeviceSpec& spec, std::deque<V4l2Frame> frames) {
  {
    std::lock_guard lock(mutex_);
    spec_ = spec;
    frames_ = std::move(frames);
    format_ = spec.formats.empty() ? V4L2_PIX_FMT_Y10 : spec.formats.front();
    bufs_.clear();
    streaming_ = false;
    present_ = true;
    gone_ = true;  // until the new node file exists: a client must not open the old one and succeed
    served_ = 0;
    unplug_at_ = SIZE_MAX;
    sequence_ = 0;
  }
  // A replugged node gets a fresh handler registration (umockdev refuses a second one).
  if (std::find(attached_.begin(), attached_.end(), node()) != attached_.end())
    umockdev_testbed_detach_ioctl(testbed_, node().c_str(), nullptr);
  else
    attached_.push_back(node());
  if (!umockdev_testbed_attach_ioctl(testbed_, node().c_str(), handler_, nullptr))
    throw std::runtime_error("attach_ioctl " + node());
  // Node contents make umockdev create a plain file (not a pty): that file backs the MMAP buffers.
  const std::string desc = "P: /devices/emulated/video4linux/video" + std::to_string(spec.index) +
                           "\nN: video" + std::to_string(spec.index) +
                           "=00\nE: SUBSYSTEM=video4linux\nE: DEVNAME=" + node() + "\nA: name=" + spec.card +
                           "\\n\n";
  GError* err = nullptr;
  if (!umockdev_testbed_add_from_string(testbed_, desc.c_str(), &err)) {
    std::string msg = err ? err->message : "?";
    g_clear_error(&err);
    throw std::runtime_error("add_from_string: " + msg);
  }
  std::lock_guard lock(mutex_);
  gone_ = false;
}

void V4l2Emulator::unplug_after(std::size_t frames) {
  std::lock_guard lock(mutex_);
  unplug_at_ = served_ + frames;
  if (frames == 0) remove_locked();
}

void V4l2Emulator::remove_locked() {
  if (gone_) return;
  gone_ = true;
  present_ = false;
  umockdev_testbed_uevent(testbed_, syspath().c_str(), "remove");
  // remove_device() only unlinks nodes of devices with a "dev" (major:minor) attribute: without this a
  // client could reopen the dead node and talk to a handler that is about to be detached.
  gchar* root = umockdev_testbed_get_root_dir(testbed_);
  ::unlink((std::string(root) + node()).c_str());
  g_free(root);
  umockdev_testbed_remove_device(testbed_, syspath().c_str());
}

bool V4l2Emulator::unplugged() const {
  std::lock_guard lock(mutex_);
  return gone_;
}
std::size_t V4l2Emulator::frames_served() const {
  std::lock_guard lock(mutex_);
  return served_;
}
std::uint32_t V4l2Emulator::chosen_format() const {
  std::lock_guard lock(mutex_);
  return format_;
}
bool V4l2Emulator::streaming() const {
  std::lock_guard lock(mutex_);
  return streaming_;
}

gboolean V4l2Emulator::on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  auto* emu = static_cast<V4l2Emulator*>(self);
  const bool handled = emu->handle(client);
  // The node is a plain file, so poll() always says ready: pause on "no frame yet" instead of spinning.
  if (emu->idle_.exchange(false)) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return handled ? TRUE : FALSE;
}

namespace {
template <class T>
T* resolve(UMockdevIoctlData* arg, UMockdevIoctlData*& holder) {
  holder = umockdev_ioctl_data_resolve(arg, 0, sizeof(T), nullptr);
  return reinterpret_cast<T*>(holder->data);
}
}  // namespace

bool V4l2Emulator::handle(UMockdevIoctlClient* client) {
  const unsigned long request = umockdev_ioctl_client_get_request(client);
  UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
  std::lock_guard lock(mutex_);
  const bool stale = node() != umockdev_ioctl_client_get_devnode(client);
  if (gone_ || stale) {
    umockdev_ioctl_client_complete(client, -1, ENODEV);
    return true;
  }
  UMockdevIoctlData* d = nullptr;
  long result = 0;
  int err = 0;
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* c = resolve<v4l2_capability>(arg, d);
      std::memset(c, 0, sizeof *c);
      std::snprintf(reinterpret_cast<char*>(c->driver), sizeof c->driver, "emulated");
      std::snprintf(reinterpret_cast<char*>(c->card), sizeof c->card, "%s", spec_.card.c_str());
      c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
      c->capabilities = c->device_caps | V4L2_CAP_DEVICE_CAPS;
      break;
    }
    case VIDIOC_ENUM_FMT: {
      auto* f = resolve<v4l2_fmtdesc>(arg, d);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || f->index >= spec_.formats.size()) {
        result = -1;
        err = EINVAL;
        break;
      }
      f->pixelformat = spec_.formats[f->index];
      std::snprintf(reinterpret_cast<char*>(f->description), sizeof f->description, "fmt %u", f->index);
      break;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* s = resolve<v4l2_frmsizeenum>(arg, d);
      if (s->index > 0 ||
          std::find(spec_.formats.begin(), spec_.formats.end(), s->pixel_format) == spec_.formats.end()) {
        result = -1;
        err = EINVAL;
        break;
      }
      s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
      s->discrete = {spec_.width, spec_.height};
      break;
    }
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT: {
      auto* f = resolve<v4l2_format>(arg, d);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
        result = -1;
        err = EINVAL;
        break;
      }
      std::uint32_t want = f->fmt.pix.pixelformat;
      if (request == VIDIOC_G_FMT ||
          std::find(spec_.formats.begin(), spec_.formats.end(), want) == spec_.formats.end())
        want = format_;
      if (request == VIDIOC_S_FMT) {
        if (streaming_ || !bufs_.empty()) {
          result = -1;
          err = EBUSY;
          break;
        }
        format_ = want;
      }
      f->fmt.pix.pixelformat = want;
      f->fmt.pix.width = spec_.width;  // a fixed-size sensor bridge: the size is not negotiable
      f->fmt.pix.height = spec_.height;
      f->fmt.pix.field = V4L2_FIELD_NONE;
      f->fmt.pix.bytesperline = spec_.width * bytes_per_pixel(want);
      f->fmt.pix.sizeimage = f->fmt.pix.bytesperline * spec_.height;
      break;
    }
    case VIDIOC_REQBUFS: {
      auto* r = resolve<v4l2_requestbuffers>(arg, d);
      if (r->memory != V4L2_MEMORY_MMAP) {
        result = -1;
        err = EINVAL;
        break;
      }
      r->count = std::min<std::uint32_t>(r->count, 8);
      const std::size_t page = static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
      buf_span_ = (image_size() + page - 1) / page * page;
      bufs_.assign(r->count, Buf{});
      for (std::size_t i = 0; i < bufs_.size(); ++i) bufs_[i].offset = i * buf_span_;
      gchar* root = umockdev_testbed_get_root_dir(testbed_);
      const std::string file = std::string(root) + node();
      g_free(root);
      if (const int fd = ::open(file.c_str(), O_RDWR); fd >= 0) {
        if (::ftruncate(fd, static_cast<off_t>(buf_span_ * bufs_.size())) != 0) err = errno;
        ::close(fd);
      }
      break;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF: {
      auto* b = resolve<v4l2_buffer>(arg, d);
      if (b->index >= bufs_.size()) {
        result = -1;
        err = EINVAL;
        break;
      }
      b->m.offset = static_cast<std::uint32_t>(bufs_[b->index].offset);
      b->length = static_cast<std::uint32_t>(image_size());
      if (request == VIDIOC_QBUF) bufs_[b->index].queued = true;
      break;
    }
    case VIDIOC_DQBUF: {
      auto* b = resolve<v4l2_buffer>(arg, d);
      auto it = std::find_if(bufs_.begin(), bufs_.end(), [](const Buf& x) { return x.queued; });
      if (served_ >= unplug_at_) {
        remove_locked();
        result = -1;
        err = ENODEV;
        break;
      }
      if (!streaming_ || it == bufs_.end() || frames_.empty()) {
        idle_ = true;
        result = -1;
        err = EAGAIN;
        break;
      }
      V4l2Frame f = std::move(frames_.front());
      frames_.pop_front();
      gchar* root = umockdev_testbed_get_root_dir(testbed_);
      const std::string file = std::string(root) + node();
      g_free(root);
      const int fd = ::open(file.c_str(), O_RDWR);
      const std::size_t n = std::min(f.image.size(), image_size());
      if (fd < 0 ||
          ::pwrite(fd, f.image.data(), n, static_cast<off_t>(it->offset)) != static_cast<ssize_t>(n))
        err = EIO;
      if (fd >= 0) ::close(fd);
      it->queued = false;
      b->index = static_cast<std::uint32_t>(it - bufs_.begin());
      b->bytesused = static_cast<std::uint32_t>(n);
      b->field = f.field;
      b->sequence = sequence_++;
      b->timestamp.tv_sec = f.timestamp_ns / 1'000'000'000;
      b->timestamp.tv_usec = f.timestamp_ns % 1'000'000'000 / 1000;
      b->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | (f.error ? V4L2_BUF_FLAG_ERROR : 0u);
      ++served_;
      if (err) result = -1;
      break;
    }
    case VIDIOC_STREAMON:
      streaming_ = true;
      break;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      for (auto& b : bufs_) b.queued = false;
      break;
    default:
      result = -1;
      err = ENOTTY;
      break;
  }
  umockdev_ioctl_client_complete(client, result, err);
  if (d) g_object_unref(d);
  return true;
}

}  // namespace naneye::test
