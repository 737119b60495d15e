#pragma once
// StreamParser: the spec's "Parsing rules" over a byte stream that arrives in arbitrary chunks (USB
// transfers, file reads). Out of sync it looks for a header and confirms it by the next header
// exactly one record later with seq + 1 (at the very end of a stream by the reference pixels); in
// sync it unpacks each record straight into the frame the FrameSink lends it as bytes arrive, and
// hands the frame back the moment the record's last byte is in (never waiting for the next header).
// Only the search for sync copies bytes (into one buffer of record size allocated at construction).
//
// Counters (AtomicCounters): bytes, records, sync_losses, seq_gaps (records lost upstream, seq wraps
// 255 -> 0), cut_records (record cut short: dropped), corrupt_records (a non-padding pixel above
// 1023: bytes lost or damaged inside the record), reference_failures.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "naneye/driver/counters.hpp"
#include "naneye/driver/frame.hpp"
#include "naneye/driver/wire_format.hpp"

namespace naneye::driver {

// The spec's reference pixels: row 0 px 0, 2 black and 1, 3 saturated; last row px s-4 black, s-3
// white (s = sensor size). Thresholds and polarity are unconfirmed on hardware, hence settings.
struct ReferenceCheck {
  bool enabled = true;
  std::uint16_t black_max = 600;
  std::uint16_t white_min = 800;
  bool reject = false;  // drop failing frames (they are counted either way; Frame::reference)
};

// The check on one frame's pixels (host order, `sensor_size` a side, row-major): not_checked when
// `rc` is disabled.
ReferenceStatus check_reference(const std::uint16_t* px, int sensor_size, const ReferenceCheck& rc);

struct ParserSettings {
  // Pixels per side: 250 for NanEye Stereo; other NanEye 2D dies use 160 or 100 (any 4..250 works;
  // the frame then holds sensor_size x sensor_size pixels row-major at the start of Frame::pixels).
  int sensor_size = kSensorSize;
  ColorMode color = ColorMode::mono;
  ReferenceCheck reference;
  // A record with a non-padding pixel above 1023 is dropped (true) or delivered masked to 10 bits.
  bool reject_out_of_range = true;

  std::size_t record_size() const {
    return kHeaderSize + 2 * static_cast<std::size_t>(sensor_size) * static_cast<std::size_t>(sensor_size);
  }
};

// Where the parser puts records. begin_frame() lends a frame (nullptr: skip this record); exactly one
// of commit_frame() / abort_frame() follows for every frame lent, before the next begin_frame().
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual Frame* begin_frame(const RecordHeader& header) = 0;
  virtual void commit_frame(Frame& frame) = 0;  // complete and checked: sensor, seq, ticks, pixels set
  virtual void abort_frame(Frame& frame) = 0;   // cut, corrupt or rejected
};

class StreamParser {
 public:
  // Throws std::invalid_argument for a sensor_size outside 4..250.
  StreamParser(const ParserSettings& settings, FrameSink& sink, AtomicCounters& counters);

  // One chunk as received; `host_ns` (CLOCK_MONOTONIC) stamps the frames completed by it.
  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_ns);
  // End of the stream (end of file, device lost): a record in progress is cut; a last record that
  // no header can confirm is accepted by its reference pixels. The parser is then ready for a new
  // stream, out of sync.
  void finish(std::int64_t host_ns);

  const ParserSettings& settings() const { return settings_; }

 private:
  std::span<const std::uint8_t> feed_in_sync(std::span<const std::uint8_t> data);
  std::span<const std::uint8_t> feed_acquire(std::span<const std::uint8_t> data);
  bool scan_acquire();  // true once sync is confirmed
  std::size_t find_candidate(std::size_t from) const;
  void lose_sync();
  void deliver_buffered(const std::uint8_t* record);  // a whole record already in memory
  void finish_record();
  bool reference_ok(const std::uint8_t* pixel_bytes) const;  // pixels in wire order (u16 LE)

  ParserSettings settings_;
  FrameSink& sink_;
  AtomicCounters& counters_;
  const std::size_t record_size_;
  const std::size_t pixel_bytes_;
  const std::size_t pixel_count_;
  std::int64_t host_ns_ = 0;

  bool in_sync_ = false;
  // In sync: the record in progress.
  std::uint8_t header_[kHeaderSize] = {};
  std::size_t header_len_ = 0;
  std::uint8_t expected_seq_ = 0;
  Frame* frame_ = nullptr;  // nullptr while skipping a record the sink declined
  std::size_t pixel_done_ = 0;

  // Out of sync: bytes kept to look for and confirm a header (capacity record + header).
  std::vector<std::uint8_t> acq_;
  std::size_t acq_len_ = 0;
  std::size_t scan_pos_ = 0;
};

}  // namespace naneye::driver
