#pragma once
// The one interface every backend implements (usb://, v4l2://, file://, sim://). A source runs its
// own capture thread and hands pairs over through a lock-free single-producer/single-consumer ring;
// the consumer calls next(). Live sources drop the oldest pair when the consumer falls behind (and
// count it); replay at max speed blocks the producer instead and drops nothing.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "naneye/driver/frame.hpp"

namespace naneye::driver {

enum class SourceState { starting, streaming, waiting_for_device, stalled, finished, failed, stopped };
const char* to_string(SourceState s);
// True once a source delivers no more pairs: finished, failed or stopped (a consumer's loop ends).
bool has_ended(SourceState s);

// Every counter the parser, the pairer and the backend keep. Monotonic; read as a snapshot.
struct SourceCounters {
  std::uint64_t bytes = 0;
  std::uint64_t records = 0;              // complete records delivered by the parser
  std::uint64_t sync_losses = 0;          // header not where expected: acquisition restarted
  std::uint64_t seq_gaps = 0;             // records lost upstream (sum of seq jumps)
  std::uint64_t cut_records = 0;          // records cut short, dropped
  std::uint64_t corrupt_records = 0;      // pixel values above 1023 (misaligned or damaged bytes), dropped
  std::uint64_t reference_failures = 0;   // reference-pixel check failed
  std::uint64_t reference_unchecked = 0;  // records delivered without a reference-pixel check
  std::uint64_t unpaired = 0;             // frames that found no partner within the tolerance
  std::uint64_t pairs = 0;                // pairs handed to the consumer
  std::uint64_t pairs_dropped = 0;        // oldest pairs dropped because the consumer fell behind
  std::uint64_t reconnects = 0;
  std::uint64_t transfer_errors = 0;
  std::uint64_t stalls = 0;
};

// Every counter with its name and meaning, in one place, so that each report (`naneye replay
// --stats`, /v1/status, /metrics) lists them all: f(name, help, value).
template <typename F>
void for_each_counter(const SourceCounters& c, F&& f) {
  f("bytes", "Bytes received from the source.", c.bytes);
  f("records", "Complete records delivered by the parser.", c.records);
  f("sync_losses", "Times the parser lost and re-acquired sync.", c.sync_losses);
  f("seq_gaps", "Records lost upstream (sum of sequence jumps).", c.seq_gaps);
  f("cut_records", "Records cut short and dropped.", c.cut_records);
  f("corrupt_records", "Records with pixel values above 1023, dropped.", c.corrupt_records);
  f("reference_failures", "Records failing the reference-pixel check.", c.reference_failures);
  f("reference_unchecked",
    "Records whose reference pixels were not checked (not carried, or the check is off).",
    c.reference_unchecked);
  f("unpaired", "Frames that found no partner within the tolerance.", c.unpaired);
  f("pairs", "Pairs handed to the consumer by the source.", c.pairs);
  f("pairs_dropped", "Oldest pairs dropped because the consumer fell behind.", c.pairs_dropped);
  f("reconnects", "Device reconnections.", c.reconnects);
  f("transfer_errors", "Failed transfers.", c.transfer_errors);
  f("stalls", "Stall timeouts of the source.", c.stalls);
}

struct SourceInfo {
  std::string uri;
  std::string kind;        // "usb", "v4l2", "file", "sim"
  std::string device;      // e.g. "10f8:c487 bus 1 dev 4 serial X" or "/dev/video0", or the file path
  bool live = true;        // live: drop-oldest; replay at max speed: blocking, lossless
  double nominal_fps = 0;  // 0 when unknown
};

// Sees every transfer exactly as received, on the capture thread, before it is parsed (used by
// `naneye record`). Must be quick: it runs in the capture path.
class RawTap {
 public:
  virtual ~RawTap() = default;
  virtual void on_bytes(std::span<const std::uint8_t> bytes, std::int64_t host_ns) = 0;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void start() = 0;  // starts the capture thread; errors opening the source throw SourceError
  virtual void stop() = 0;   // cancels everything in flight and joins; idempotent
  // The next pair, or nullptr after `timeout` or once the source is finished/stopped (see state()).
  virtual PairPtr next(std::chrono::milliseconds timeout) = 0;
  virtual SourceState state() const = 0;
  virtual SourceCounters counters() const = 0;
  virtual SourceInfo info() const = 0;
  // Set when state() is failed, or for a replay that ended on a damaged file (where in it, and why).
  virtual std::optional<std::string> error() const = 0;
  // Installs a tap for the raw bytes (before start(); nullptr removes it). Sources that have no raw
  // byte stream (e.g. a simulator producing frames directly) return false; recorders then re-encode.
  virtual bool set_raw_tap(RawTap* tap) {
    (void)tap;
    return false;
  }
};

// Bad URIs, bad parameters, devices or files that cannot be opened.
class SourceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace naneye::driver
