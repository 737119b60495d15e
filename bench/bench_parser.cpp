// Parser throughput against a plain memcpy of the same bytes (the physical limit), in one run.
// The camera needs 15.5 MB/s (2 x 125 008 B x 62 fps); the target is >= 1 GB/s.
// Each benchmark moves a 64-record stream (8 MB) in transfer-sized chunks (argument, bytes).
#include <benchmark/benchmark.h>

#include <cstring>
#include <vector>

#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"
#include "naneye/driver/pairer.hpp"
#include "naneye/driver/stream_parser.hpp"
#include "naneye/driver/wire_format.hpp"

namespace {

using namespace naneye::driver;

const std::vector<std::uint8_t>& stream() {
  static const std::vector<std::uint8_t> bytes = [] {
    std::vector<std::uint8_t> out(64 * kRecordSize);
    std::vector<std::uint16_t> px(kPixelCount);
    for (std::size_t i = 0; i < kPixelCount; ++i) px[i] = static_cast<std::uint16_t>((i * 7) % 1024);
    px[0] = px[2] = 40;
    px[1] = px[3] = 1000;
    px[249 * 250 + 246] = 30;
    px[249 * 250 + 247] = 990;
    for (int k = 0; k < 64; ++k)
      encode_record(RecordHeader{static_cast<std::uint8_t>(k), static_cast<Sensor>(k % 2),
                                 static_cast<std::uint32_t>(k / 2) * 1'089'600u + (k % 2) * 100'000u},
                    std::span<const std::uint16_t, kPixelCount>(px.data(), kPixelCount),
                    std::span<std::uint8_t, kRecordSize>(out.data() + k * kRecordSize, kRecordSize));
    return out;
  }();
  return bytes;
}

void BM_Memcpy(benchmark::State& state) {
  const auto& s = stream();
  const auto chunk = static_cast<std::size_t>(state.range(0));
  std::vector<std::uint8_t> dst(s.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < s.size(); i += chunk)
      std::memcpy(dst.data() + i, s.data() + i, std::min(chunk, s.size() - i));
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * s.size()));
}

// Parser alone, into two frame buffers (no pairing).
struct NullSink : FrameSink {
  Frame frames[2];
  std::uint64_t n = 0;
  Frame* begin_frame(const RecordHeader& h) override { return &frames[static_cast<int>(h.sensor)]; }
  void commit_frame(Frame&) override { ++n; }
  void abort_frame(Frame&) override {}
};

void BM_Parser(benchmark::State& state) {
  const auto& s = stream();
  const auto chunk = static_cast<std::size_t>(state.range(0));
  NullSink sink;
  AtomicCounters counters;
  StreamParser parser(ParserSettings{}, sink, counters);
  for (auto _ : state) {
    for (std::size_t i = 0; i < s.size(); i += chunk)
      parser.feed(std::span(s).subspan(i, std::min(chunk, s.size() - i)), 0);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * s.size()));
  state.counters["records"] = static_cast<double>(sink.n);
}

// The whole capture path: parser -> pairer -> pool -> ring -> consumer (inline, same thread).
struct RingChannel : PairChannel {
  PairPool pool{17};
  PairRing ring{4, PairRing::Policy::drop_oldest, pool.deleter()};
  PairPtr acquire() override {
    PairPtr p = pool.try_acquire();
    while (!p && ring.drop_oldest()) p = pool.try_acquire();
    return p;
  }
  void deliver(PairPtr p) override { ring.push(std::move(p)); }
};

void BM_ParserPairerRing(benchmark::State& state) {
  const auto& s = stream();
  const auto chunk = static_cast<std::size_t>(state.range(0));
  RingChannel channel;
  AtomicCounters counters;
  Pairer pairer(PairerSettings{}, channel, counters);
  StreamParser parser(ParserSettings{}, pairer, counters);
  std::uint64_t pairs = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < s.size(); i += chunk) {
      parser.feed(std::span(s).subspan(i, std::min(chunk, s.size() - i)), 0);
      while (PairPtr p = channel.ring.try_pop()) ++pairs;
    }
    parser.finish(0);
    pairer.flush(true);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * s.size()));
  state.counters["pairs"] = static_cast<double>(pairs);
  state.counters["dropped"] = static_cast<double>(channel.ring.dropped());
}

BENCHMARK(BM_Memcpy)->Arg(16384)->Arg(512 * 1024);
BENCHMARK(BM_Parser)->Arg(16384)->Arg(512 * 1024);
BENCHMARK(BM_ParserPairerRing)->Arg(16384)->Arg(512 * 1024);

}  // namespace

BENCHMARK_MAIN();
