#include "fuzz_entries.hpp"

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "naneye/driver/neyd.hpp"
#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pairer.hpp"
#include "naneye/driver/stream_parser.hpp"

namespace naneye::fuzz {
namespace {

using namespace naneye::driver;

// The pool outlives every input: building 12 full 250 x 250 pairs per input held the fuzzer at
// ~200 exec/s. Each input gets a fresh parser, pairer and counters (cheap), and must hand every
// buffer back (checked in finish()), so reusing the pool cannot carry state across inputs.
struct DropChannel : PairChannel {
  PairPool pool{12};
  std::uint64_t delivered = 0;
  PairPtr acquire() override { return pool.try_acquire(); }
  void deliver(PairPtr p) override {
    fuzz_check(p->left.sensor == Sensor::left && p->right.sensor == Sensor::right);
    ++delivered;
  }
};

DropChannel& shared_channel() {
  static DropChannel channel;
  channel.delivered = 0;
  return channel;
}

// Parser + pairer over one stream; checks the counters against the bytes.
struct Pipeline {
  DropChannel& channel = shared_channel();
  AtomicCounters counters;
  Pairer pairer;
  StreamParser parser;
  explicit Pipeline(const ParserSettings& s)
      : pairer(PairerSettings{}, channel, counters), parser(s, pairer, counters) {}
  void finish(std::size_t bytes, std::size_t record_size) {
    parser.finish(0);
    pairer.flush();
    const SourceCounters c = counters.snapshot();
    fuzz_check(c.bytes == bytes);
    fuzz_check(c.records <= bytes / record_size);
    fuzz_check(2 * channel.delivered + c.unpaired == c.records);
    fuzz_check(channel.pool.available() == channel.pool.capacity());
  }
};

}  // namespace

int parse_stream(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  ParserSettings s;
  static constexpr int kSizes[] = {4, 5, 8, 250};
  s.sensor_size = kSizes[data[1] & 3];
  s.reject_out_of_range = (data[1] & 4) == 0;
  s.reference.enabled = (data[1] & 8) == 0;
  s.reference.reject = (data[1] & 16) != 0;
  s.color = (data[1] & 32) ? ColorMode::bayer_grbg : ColorMode::mono;
  const std::size_t chunk = 1 + data[0] % 97;
  Pipeline p(s);
  const std::uint8_t* b = data + 2;
  const std::size_t n = size - 2;
  for (std::size_t i = 0; i < n; i += chunk)
    p.parser.feed(std::span<const std::uint8_t>(b + i, std::min(chunk, n - i)), static_cast<std::int64_t>(i));
  p.finish(n, s.record_size());
  return 0;
}

int read_neyd(const std::uint8_t* data, std::size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  ParserSettings s;
  s.sensor_size = 4;
  Pipeline p(s);
  std::size_t fed = 0;
  try {
    NeydReader reader(in);
    // Kept across inputs, as a source keeps its own: the reader reuses its capacity.
    static std::vector<std::uint8_t> chunk;
    std::int64_t t = 0;
    while (reader.next(chunk, t)) {
      fuzz_check(chunk.size() <= kNeydMaxChunk);
      p.parser.feed(chunk, t);
      fed += chunk.size();
    }
  } catch (const NeydError& e) {
    fuzz_check(e.offset() <= size);
    fuzz_check(std::string(e.what()).find("byte offset") != std::string::npos || e.offset() == 0);
  }
  p.finish(fed, s.record_size());
  return 0;
}

}  // namespace naneye::fuzz
