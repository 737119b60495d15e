#include "naneye/driver/stream_parser.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <stdexcept>

namespace naneye::driver {
namespace {

// Only bytes 1..3 decide whether a header is one (the spec's test, sensor id 0 or 1).
bool looks_like_header(const std::uint8_t* b) {
  return (b[1] & 0xF0) == 0xB0 && (b[1] & 0x0F) <= 1 && b[2] == 0xFE && b[3] == 0xCA;
}

RecordHeader header_at(const std::uint8_t* b) {
  return *decode_header(std::span<const std::uint8_t, kHeaderSize>(b, kHeaderSize));
}

// Any pixel with bits 10..15 set? Four pixels per 64-bit word (compilers vectorise this loop
// further); independent of endianness because the mask is symmetric in each 16-bit lane.
bool any_out_of_range(const std::uint16_t* px, std::size_t n) {
  constexpr std::uint64_t kHigh = 0xFC00FC00FC00FC00ull;
  std::uint64_t acc = 0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    std::uint64_t w;
    std::memcpy(&w, px + i, sizeof w);
    acc |= w;
  }
  for (; i < n; ++i) acc |= px[i];
  return (acc & kHigh) != 0;
}

}  // namespace

StreamParser::StreamParser(const ParserSettings& settings, FrameSink& sink, AtomicCounters& counters)
    : settings_(settings),
      sink_(sink),
      counters_(counters),
      record_size_(settings.record_size()),
      pixel_bytes_(settings.record_size() - kHeaderSize),
      pixel_count_((settings.record_size() - kHeaderSize) / 2) {
  if (settings.sensor_size < 4 || settings.sensor_size > kSensorSize)
    throw std::invalid_argument("sensor_size must be within 4..250");
  acq_.resize(record_size_ + kHeaderSize);
}

void StreamParser::feed(std::span<const std::uint8_t> bytes, std::int64_t host_ns) {
  AtomicCounters::add(counters_.bytes, bytes.size());
  host_ns_ = host_ns;
  while (!bytes.empty()) bytes = in_sync_ ? feed_in_sync(bytes) : feed_acquire(bytes);
}

std::span<const std::uint8_t> StreamParser::feed_in_sync(std::span<const std::uint8_t> data) {
  while (!data.empty()) {
    if (header_len_ < kHeaderSize) {
      const std::size_t n = std::min(kHeaderSize - header_len_, data.size());
      std::memcpy(header_ + header_len_, data.data(), n);
      header_len_ += n;
      data = data.subspan(n);
      if (header_len_ < kHeaderSize) return data;
      if (!looks_like_header(header_)) {
        lose_sync();
        return data;
      }
      const RecordHeader h = header_at(header_);
      const auto gap = static_cast<std::uint8_t>(h.seq - expected_seq_);
      if (gap != 0) AtomicCounters::add(counters_.seq_gaps, gap);
      expected_seq_ = static_cast<std::uint8_t>(h.seq + 1);
      frame_ = sink_.begin_frame(h);
      if (frame_) {
        frame_->sensor = h.sensor;
        frame_->seq = h.seq;
        frame_->ticks = h.ticks;
      }
      pixel_done_ = 0;
    }
    const std::size_t n = std::min(pixel_bytes_ - pixel_done_, data.size());
    // The frame's u16 pixels viewed as bytes: on a little-endian host the wire order is the memory
    // order, so the unpack is one copy; finish_record() swaps on big-endian hosts.
    if (frame_)
      std::memcpy(reinterpret_cast<std::uint8_t*>(frame_->pixels.data()) + pixel_done_, data.data(), n);
    pixel_done_ += n;
    data = data.subspan(n);
    if (pixel_done_ == pixel_bytes_) {
      finish_record();
      header_len_ = 0;
    }
  }
  return data;
}

void StreamParser::lose_sync() {
  AtomicCounters::add(counters_.sync_losses);
  in_sync_ = false;
  // The misplaced "header" bytes are searched again like any others.
  std::memcpy(acq_.data(), header_, kHeaderSize);
  acq_len_ = kHeaderSize;
  scan_pos_ = 0;
  header_len_ = 0;
}

std::span<const std::uint8_t> StreamParser::feed_acquire(std::span<const std::uint8_t> data) {
  while (!data.empty()) {
    if (acq_len_ == acq_.size()) {
      // Keep only what a candidate still needs (scan_pos_ is the earliest byte that can start one).
      std::memmove(acq_.data(), acq_.data() + scan_pos_, acq_len_ - scan_pos_);
      acq_len_ -= scan_pos_;
      scan_pos_ = 0;
    }
    const std::size_t n = std::min(acq_.size() - acq_len_, data.size());
    std::memcpy(acq_.data() + acq_len_, data.data(), n);
    acq_len_ += n;
    data = data.subspan(n);
    if (scan_acquire()) break;
  }
  return data;
}

std::size_t StreamParser::find_candidate(std::size_t from) const {
  const std::uint8_t* b = acq_.data();
  std::size_t q = from + 2;  // position of the 0xFE magic byte
  while (q + 1 < acq_len_) {
    const void* hit = std::memchr(b + q, 0xFE, acq_len_ - 1 - q);
    if (!hit) break;
    q = static_cast<std::size_t>(static_cast<const std::uint8_t*>(hit) - b);
    if (looks_like_header(b + q - 2)) return q - 2;
    ++q;
  }
  return acq_.size();
}

bool StreamParser::scan_acquire() {
  for (;;) {
    const std::size_t p = find_candidate(scan_pos_);
    if (p == acq_.size()) {
      scan_pos_ = std::max(scan_pos_, acq_len_ >= 3 ? acq_len_ - 3 : std::size_t{0});
      return false;
    }
    scan_pos_ = p;
    if (p + record_size_ + kHeaderSize > acq_len_) return false;
    const std::uint8_t* b = acq_.data() + p;
    const std::uint8_t* next = b + record_size_;
    if (looks_like_header(next) && header_at(next).seq == static_cast<std::uint8_t>(header_at(b).seq + 1)) {
      // Confirmed. What follows the record (at most one header, since the buffer holds one record
      // and one header) goes through the in-sync path.
      std::uint8_t rest[kHeaderSize];
      const std::size_t rest_len = acq_len_ - (p + record_size_);
      std::memcpy(rest, next, rest_len);
      acq_len_ = 0;
      scan_pos_ = 0;
      in_sync_ = true;
      header_len_ = 0;
      deliver_buffered(b);
      feed_in_sync(std::span<const std::uint8_t>(rest, rest_len));
      return true;
    }
    scan_pos_ = p + 1;
  }
}

void StreamParser::deliver_buffered(const std::uint8_t* record) {
  const RecordHeader h = header_at(record);
  expected_seq_ = static_cast<std::uint8_t>(h.seq + 1);
  frame_ = sink_.begin_frame(h);
  if (!frame_) return;
  frame_->sensor = h.sensor;
  frame_->seq = h.seq;
  frame_->ticks = h.ticks;
  std::memcpy(frame_->pixels.data(), record + kHeaderSize, pixel_bytes_);
  finish_record();
}

void StreamParser::finish_record() {
  if (!frame_) return;
  Frame& f = *frame_;
  frame_ = nullptr;
  std::uint16_t* px = f.pixels.data();
  if constexpr (std::endian::native == std::endian::big)
    for (std::size_t i = 0; i < pixel_count_; ++i)
      px[i] = static_cast<std::uint16_t>(px[i] >> 8 | px[i] << 8);
  f.reference = check_reference(px, settings_.sensor_size, settings_.reference);
  f.host_ns = host_ns_;
  f.color = settings_.color;

  // One vectorisable OR over the record; only if it shows high bits do we look closer, because
  // padding pixels may legitimately hold anything.
  if (any_out_of_range(px, pixel_count_)) {
    const int s = settings_.sensor_size;
    bool bad = false;
    for (int r = 0; r < s; ++r)
      for (int c = 0; c < s; ++c) {
        std::uint16_t& v = px[static_cast<std::size_t>(r) * s + c];
        const bool padding = c == s - 1 || (r == s - 1 && c >= s - 2);
        if (v > kPixelMax && !padding) {
          bad = true;
          v &= kPixelMax;
        }
      }
    if (bad) {
      AtomicCounters::add(counters_.corrupt_records);
      if (settings_.reject_out_of_range) {
        sink_.abort_frame(f);
        return;
      }
    }
  }
  if (f.reference == ReferenceStatus::not_checked) AtomicCounters::add(counters_.reference_unchecked);
  if (f.reference == ReferenceStatus::failed) {
    AtomicCounters::add(counters_.reference_failures);
    if (settings_.reference.reject) {
      sink_.abort_frame(f);
      return;
    }
  }
  AtomicCounters::add(counters_.records);
  sink_.commit_frame(f);
}

bool StreamParser::reference_ok(const std::uint8_t* pixel_bytes) const {
  const ReferenceCheck& rc = settings_.reference;
  if (!rc.enabled) return true;
  const auto s = static_cast<std::size_t>(settings_.sensor_size);
  const auto px = [&](std::size_t i) {
    return static_cast<std::uint16_t>(pixel_bytes[2 * i] | pixel_bytes[2 * i + 1] << 8);
  };
  const std::size_t last = (s - 1) * s;
  return px(0) <= rc.black_max && px(2) <= rc.black_max && px(1) >= rc.white_min && px(3) >= rc.white_min &&
         px(last + s - 4) <= rc.black_max && px(last + s - 3) >= rc.white_min;
}

ReferenceStatus check_reference(const std::uint16_t* px, int sensor_size, const ReferenceCheck& rc) {
  if (!rc.enabled) return ReferenceStatus::not_checked;
  const auto s = static_cast<std::size_t>(sensor_size);
  const std::size_t last = (s - 1) * s;
  const bool ok = px[0] <= rc.black_max && px[2] <= rc.black_max && px[1] >= rc.white_min &&
                  px[3] >= rc.white_min && px[last + s - 4] <= rc.black_max &&
                  px[last + s - 3] >= rc.white_min;
  return ok ? ReferenceStatus::passed : ReferenceStatus::failed;
}

void StreamParser::finish(std::int64_t host_ns) {
  host_ns_ = host_ns;
  if (in_sync_) {
    if (header_len_ > 0) {
      AtomicCounters::add(counters_.cut_records);
      if (frame_) sink_.abort_frame(*frame_);
      frame_ = nullptr;
    }
  } else {
    // No header can follow any more: a complete last record is confirmed by its reference pixels
    // alone (with the check disabled, a complete record with a valid header is taken as it is).
    for (std::size_t p = find_candidate(scan_pos_); p != acq_.size(); p = find_candidate(p + 1)) {
      if (p + record_size_ > acq_len_) {
        AtomicCounters::add(counters_.cut_records);
        break;
      }
      const std::uint8_t* b = acq_.data() + p;
      if (!reference_ok(b + kHeaderSize)) continue;
      deliver_buffered(b);
      if (acq_len_ > p + record_size_) AtomicCounters::add(counters_.cut_records);
      break;
    }
  }
  in_sync_ = false;
  header_len_ = 0;
  acq_len_ = 0;
  scan_pos_ = 0;
}

}  // namespace naneye::driver
