#include "naneye/driver/recorder.hpp"

#include <time.h>

#include <charconv>
#include <chrono>
#include <vector>

#include "naneye/base/clock.hpp"
#include "naneye/driver/byte_stream_source.hpp"
#include "naneye/driver/neyd.hpp"

namespace naneye::driver {
namespace {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// "10f8:c487 ..." -> ids, for USB sources.
void usb_ids(const SourceInfo& info, NeydHeader& h) {
  if (info.kind != "usb" || info.device.size() < 9 || info.device[4] != ':') return;
  unsigned v = 0, p = 0;
  if (std::from_chars(info.device.data(), info.device.data() + 4, v, 16).ec == std::errc() &&
      std::from_chars(info.device.data() + 5, info.device.data() + 9, p, 16).ec == std::errc()) {
    h.usb_vid = static_cast<std::uint16_t>(v);
    h.usb_pid = static_cast<std::uint16_t>(p);
  }
}

class NeydTap : public RawTap {
 public:
  explicit NeydTap(NeydWriter& w) : w_(w) {}
  void on_bytes(std::span<const std::uint8_t> bytes, std::int64_t host_ns) override {
    w_.write_chunk(bytes, host_ns);
  }

 private:
  NeydWriter& w_;
};

}  // namespace

RecordSummary record_to_neyd(FrameSource& source, const std::string& path, const RecordLimits& limits,
                             const std::atomic<bool>* interrupt) {
  const SourceInfo info = source.info();
  NeydHeader h;
  h.start_wall_ns = base::wall_ns();
  h.start_monotonic_ns = base::monotonic_ns();
  usb_ids(info, h);
  h.note = "{\"uri\":" + json_string(info.uri) + ",\"kind\":" + json_string(info.kind) +
           ",\"device\":" + json_string(info.device) + "}";
  NeydWriter writer(path, h);
  NeydTap tap(writer);
  RecordSummary sum;
  sum.raw = source.set_raw_tap(&tap);
  std::vector<std::uint8_t> encoded(sum.raw ? 0 : 2 * kRecordSize);

  source.start();
  // Data reaches the kernel at least every kFlushEvery: a SIGKILL (or a crash) loses at most that
  // much: the loop below flushes once kFlushEvery / 2 has passed and waits at most kFlushEvery / 4.
  constexpr auto kFlushEvery = std::chrono::milliseconds(100);
  auto last_flush = std::chrono::steady_clock::now();
  const auto deadline = limits.seconds
                            ? std::chrono::steady_clock::now() +
                                  std::chrono::nanoseconds(static_cast<std::int64_t>(*limits.seconds * 1e9))
                            : std::chrono::steady_clock::time_point::max();
  while (!(limits.pairs && sum.pairs >= *limits.pairs)) {
    if (interrupt && interrupt->load()) break;
    auto now = std::chrono::steady_clock::now();
    if (now - last_flush >= kFlushEvery / 2) {
      writer.flush();
      last_flush = now;
    }
    // A failed write (a full disk, a quota, an I/O error) ends the recording at once: the file
    // holds every whole chunk written before it.
    if (writer.error()) break;
    now = std::chrono::steady_clock::now();
    if (now >= deadline) break;
    const auto wait = std::min<std::chrono::steady_clock::duration>(deadline - now, kFlushEvery / 4);
    PairPtr p = source.next(std::chrono::duration_cast<std::chrono::milliseconds>(wait) +
                            std::chrono::milliseconds(1));
    if (!p) {
      if (has_ended(source.state())) break;
      continue;
    }
    ++sum.pairs;
    if (!sum.raw) {
      // Stream order is seq order (seq counts records across both sensors, modulo 256).
      const bool left_first = static_cast<std::uint8_t>(p->right.seq - p->left.seq) < 128;
      const Frame* order[2] = {left_first ? &p->left : &p->right, left_first ? &p->right : &p->left};
      for (int i = 0; i < 2; ++i)
        encode_record(RecordHeader{order[i]->seq, order[i]->sensor, order[i]->ticks}, order[i]->pixels,
                      std::span<std::uint8_t, kRecordSize>(encoded.data() + i * kRecordSize, kRecordSize));
      writer.write_chunk(encoded, std::max(p->left.host_ns, p->right.host_ns));
    }
  }
  source.stop();
  source.set_raw_tap(nullptr);
  try {
    writer.close();
  } catch (const SourceError& e) {
    sum.write_error = e.what();
  }
  sum.chunks = writer.chunks();
  sum.bytes = writer.payload_bytes();
  sum.end_state = source.state();
  sum.counters = source.counters();
  sum.error = source.error();
  return sum;
}

}  // namespace naneye::driver
