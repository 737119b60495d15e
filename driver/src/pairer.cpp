#include "naneye/driver/pairer.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <limits>

namespace naneye::driver {
namespace {

constexpr std::uint8_t bit(int sensor) {
  return static_cast<std::uint8_t>(1u << sensor);
}
constexpr std::int64_t kNewStreamJump = static_cast<std::int64_t>(kTickHz);  // 1 s back: a new stream

}  // namespace

Pairer::Pairer(const PairerSettings& settings, PairChannel& channel, AtomicCounters& counters)
    : settings_(settings),
      channel_(channel),
      counters_(counters),
      tolerance_ticks_(settings.tolerance_ns * 6 / 125),
      slots_(2 * settings.max_pending + 1) {}

void Pairer::release(Slot& s, bool unpaired) {
  if (unpaired && s.filled)
    AtomicCounters::add(counters_.unpaired, std::popcount(static_cast<unsigned>(s.filled)));
  s.pair.reset();
  s.filled = s.writing = 0;
}

void Pairer::expire(std::int64_t t, int sensor) {
  const int other = 1 - sensor;
  std::size_t waiting_same = 0;
  Slot* oldest_same = nullptr;
  for (Slot& s : slots_) {
    if (!s.pair || s.writing || !s.filled) continue;
    const int held = (s.filled & bit(0)) ? 0 : 1;
    if (t < s.t[held] - kNewStreamJump) {
      release(s, true);
      continue;
    }
    if (held == other && t > s.t[held] + tolerance_ticks_) {
      release(s, true);
      continue;
    }
    if (held == sensor) {
      ++waiting_same;
      if (!oldest_same || s.t[held] < oldest_same->t[sensor]) oldest_same = &s;
    }
  }
  if (waiting_same >= settings_.max_pending && oldest_same) release(*oldest_same, true);
}

Frame* Pairer::begin_frame(const RecordHeader& h) {
  const int sensor = static_cast<int>(h.sensor);
  const int other = 1 - sensor;
  const std::int64_t t = ticks_.peek_first(h.ticks);
  expire(t, sensor);

  Slot* best = nullptr;
  std::int64_t best_dt = std::numeric_limits<std::int64_t>::max();
  for (Slot& s : slots_) {
    if (!s.pair || s.writing || s.filled != bit(other)) continue;
    const std::int64_t dt = std::llabs(s.t[other] - t);
    if (dt <= tolerance_ticks_ && dt < best_dt) {
      best = &s;
      best_dt = dt;
    }
  }
  if (!best) {
    for (Slot& s : slots_)
      if (!s.pair) {
        best = &s;
        break;
      }
    if (!best) return nullptr;  // cannot happen: expire() keeps a free slot
    best->pair = channel_.acquire();
    if (!best->pair) return nullptr;
  }
  best->writing = bit(sensor);
  current_ = best;
  Frame& f = sensor == 0 ? best->pair->left : best->pair->right;
  f.ticks64 = static_cast<std::uint64_t>(std::max<std::int64_t>(t, 0));
  f.sensor_ns = ticks_to_ns(std::max<std::int64_t>(t, 0));
  return &f;
}

void Pairer::commit_frame(Frame& frame) {
  Slot& s = *current_;
  current_ = nullptr;
  const int sensor = static_cast<int>(frame.sensor);
  ticks_.commit(frame.ticks);
  s.writing = 0;
  s.filled |= bit(sensor);
  s.t[sensor] = static_cast<std::int64_t>(frame.ticks64);
  if (s.filled == (bit(0) | bit(1))) {
    s.pair->index = next_index_++;
    PairPtr done = std::move(s.pair);
    s.filled = 0;
    channel_.deliver(std::move(done));
  }
}

void Pairer::abort_frame(Frame&) {
  Slot& s = *current_;
  current_ = nullptr;
  s.writing = 0;
  if (!s.filled) s.pair.reset();
}

void Pairer::flush(bool continue_time) {
  for (Slot& s : slots_)
    if (s.pair) release(s, true);
  current_ = nullptr;
  if (continue_time)
    ticks_.restart();
  else
    ticks_ = TickExtender{};
}

std::size_t Pairer::waiting() const {
  return static_cast<std::size_t>(
      std::count_if(slots_.begin(), slots_.end(), [](const Slot& s) { return s.pair != nullptr; }));
}

}  // namespace naneye::driver
