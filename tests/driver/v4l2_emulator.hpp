#pragma once
// An emulated V4L2 capture node for hardware-free tests: a umockdev "handle-ioctl" handler answers
// QUERYCAP, ENUM_FMT, ENUM_FRAMESIZES, G/S/TRY_FMT, REQBUFS, QUERYBUF, QBUF/DQBUF, STREAMON/OFF.
// MMAP buffers live in the testbed's plain-file device node: the client maps that file and the
// handler writes each frame into it at the buffer's offset before DQBUF returns.
#include <umockdev.h>

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <vector>

namespace naneye::test {

struct V4l2Frame {
  std::vector<std::uint8_t> image;  // stride * height bytes
  std::uint32_t field = 1;          // V4L2_FIELD_NONE
  std::int64_t timestamp_ns = 0;
  bool error = false;
};

struct V4l2DeviceSpec {
  int index = 0;  // /dev/video<index>
  std::uint32_t width = 500, height = 250;
  std::vector<std::uint32_t> formats;  // fourccs offered, first is the default
  std::string card = "NanEye emulated grabber";
};

class V4l2Emulator {
 public:
  V4l2Emulator();
  ~V4l2Emulator();
  V4l2Emulator(const V4l2Emulator&) = delete;
  V4l2Emulator& operator=(const V4l2Emulator&) = delete;

  // `testbed`: share one with other emulators (nullptr: own one).
  void plug(const V4l2DeviceSpec& spec, std::deque<V4l2Frame> frames);
  // After `frames` more frames DQBUF fails with ENODEV and the node disappears.
  void unplug_after(std::size_t frames);
  bool unplugged() const;
  std::size_t frames_served() const;
  std::uint32_t chosen_format() const;
  bool streaming() const;

  static std::uint32_t bytes_per_pixel(std::uint32_t fourcc);

 private:
  struct Buf {
    bool queued = false;
    std::size_t offset = 0;
  };
  static gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self);
  bool handle(UMockdevIoctlClient* client);
  void remove_locked();
  std::string node() const { return "/dev/video" + std::to_string(spec_.index); }
  std::string syspath() const {
    return "/sys/devices/emulated/video4linux/video" + std::to_string(spec_.index);
  }
  std::size_t stride() const { return spec_.width * bytes_per_pixel(format_); }
  std::size_t image_size() const { return stride() * spec_.height; }

  UMockdevTestbed* testbed_ = nullptr;
  UMockdevIoctlBase* handler_ = nullptr;
  mutable std::mutex mutex_;
  V4l2DeviceSpec spec_;
  std::deque<V4l2Frame> frames_;
  std::uint32_t format_ = 0;
  std::vector<Buf> bufs_;
  std::size_t buf_span_ = 0;
  bool streaming_ = false;
  bool present_ = false, gone_ = false;
  std::size_t served_ = 0, unplug_at_ = SIZE_MAX;
  std::uint32_t sequence_ = 0;
  std::vector<std::string> attached_;
  std::atomic<bool> idle_{false};
};

}  // namespace naneye::test
