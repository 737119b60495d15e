#pragma once
// .neyd, the project's capture container (docs/dump-format.md): a versioned header, then one chunk
// per USB transfer (host CLOCK_MONOTONIC arrival time, length, CRC32 of the bytes, the bytes exactly
// as received), then an end marker. Replay feeds the chunks to the very parser live capture runs.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <istream>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "naneye/driver/frame_source.hpp"

namespace naneye::driver {

inline constexpr std::uint16_t kNeydVersion = 1;
inline constexpr std::size_t kNeydMaxChunk = 64u << 20;  // larger lengths mean a damaged file
inline constexpr std::size_t kNeydMaxNote = 1u << 20;

struct NeydHeader {
  std::uint16_t version = kNeydVersion;
  std::uint16_t usb_vid = 0, usb_pid = 0;  // 0 when the source was not a USB board
  std::int64_t start_wall_ns = 0;          // CLOCK_REALTIME at capture start
  std::int64_t start_monotonic_ns = 0;     // CLOCK_MONOTONIC at capture start (chunk times' clock)
  std::string note;                        // free text, by convention JSON (source URI, device, ...)
};

// A damaged or truncated file: what() says where (byte offset, chunk index) and what is wrong.
class NeydError : public SourceError {
 public:
  NeydError(const std::string& what, std::uint64_t offset, std::uint64_t chunk)
      : SourceError(what), offset_(offset), chunk_(chunk) {}
  std::uint64_t offset() const { return offset_; }
  std::uint64_t chunk() const { return chunk_; }

 private:
  std::uint64_t offset_, chunk_;
};

class NeydWriter {
 public:
  // Creates (truncates) `path` and writes the header; throws SourceError if it cannot.
  NeydWriter(const std::string& path, const NeydHeader& header);
  ~NeydWriter();  // closes without an end marker if close() was not called (the file reads as truncated)
  NeydWriter(const NeydWriter&) = delete;
  NeydWriter& operator=(const NeydWriter&) = delete;

  // Buffered; safe against flush() from another thread. Does nothing once a write has failed.
  void write_chunk(std::span<const std::uint8_t> bytes, std::int64_t host_ns);
  // Hands what is buffered to the kernel (whole chunks only); a failure is kept in error().
  void flush();
  // The first write error ("PATH: write failed: No space left on device"), if any.
  std::optional<std::string> error() const;
  // Writes the end marker (unless a write failed) and closes; throws SourceError on an I/O error.
  void close();
  // Chunks and payload bytes written; after a write error, those known to be in the file (as of
  // the last successful flush).
  std::uint64_t chunks() const;
  std::uint64_t payload_bytes() const;

 private:
  void put(const void* data, std::size_t n);
  void fail(int err);
  std::FILE* file_ = nullptr;
  std::string path_;
  mutable std::mutex io_mu_;              // write_chunk() (source thread) against flush() (recorder thread)
  std::uint64_t chunks_ = 0, bytes_ = 0;  // under io_mu_
  std::uint64_t flushed_chunks_ = 0, flushed_bytes_ = 0;  // as of the last successful flush(), under io_mu_
  std::atomic<bool> failed_{false};
  mutable std::mutex error_mu_;
  std::string error_;  // the first failure, written once under error_mu_
};

class NeydReader {
 public:
  // Opens `path` and reads the header (throws NeydError / SourceError).
  static bool is_neyd(const std::string& path);  // by magic
  explicit NeydReader(const std::string& path);
  // Reads from a stream (fuzzing, tests); the stream must outlive the reader.
  explicit NeydReader(std::istream& in);

  const NeydHeader& header() const { return header_; }
  // The next chunk into `data` (its capacity is reused) and its arrival time. false at the end
  // marker; NeydError for anything else (truncation, bad tag, CRC mismatch, counts).
  bool next(std::vector<std::uint8_t>& data, std::int64_t& host_ns);
  std::uint64_t offset() const { return offset_; }  // bytes consumed so far

 private:
  void read_header();
  std::size_t read(void* out, std::size_t n);
  [[noreturn]] void fail(const std::string& what, std::uint64_t at) const;

  std::unique_ptr<std::istream> owned_;
  std::istream* in_ = nullptr;
  std::string name_;
  NeydHeader header_;
  std::uint64_t offset_ = 0, chunk_ = 0, payload_ = 0;
  bool ended_ = false;
};

}  // namespace naneye::driver
