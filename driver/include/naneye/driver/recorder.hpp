#pragma once
// Records any FrameSource into a .neyd file. Byte-stream sources are tapped (RawTap): every transfer
// is stored exactly as received, on the capture thread. Sources without raw bytes (a simulator) are
// re-encoded: each pair becomes one chunk of two records (encode_record), in seq order.
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "naneye/driver/frame_source.hpp"

namespace naneye::driver {

struct RecordLimits {
  std::optional<std::uint64_t> pairs;  // stop after this many pairs
  std::optional<double> seconds;       // stop after this long
};

struct RecordSummary {
  std::uint64_t pairs = 0;
  std::uint64_t chunks = 0;
  std::uint64_t bytes = 0;
  bool raw = false;  // true: bytes as received; false: re-encoded records
  SourceState end_state = SourceState::stopped;
  SourceCounters counters;
  std::optional<std::string> error;  // the source's error(), if it ended failed
  // The file's first write error (ENOSPC, EFBIG, EIO...): the recording stopped there, and the
  // file holds every whole chunk before it (it reads as truncated: no end marker).
  std::optional<std::string> write_error;
};

// Starts `source` (not yet started), records until a limit, the source's end, `interrupt` or a
// write error, stops it and closes the file; buffered data is flushed at least every 100 ms.
// Throws SourceError if the file or the source cannot be opened; a later write error is in the
// summary (write_error). The file is created 0640.
RecordSummary record_to_neyd(FrameSource& source, const std::string& path, const RecordLimits& limits,
                             const std::atomic<bool>* interrupt = nullptr);

}  // namespace naneye::driver
