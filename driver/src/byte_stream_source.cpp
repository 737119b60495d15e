#include "naneye/driver/byte_stream_source.hpp"

#include "log.hpp"
#include "naneye/base/clock.hpp"

namespace naneye::driver {

// Pool + ring seen from the pairer: a live source steals the oldest queued pair when the pool runs
// dry (the consumer is behind); a lossless one waits for the consumer.
class ByteStreamSource::Channel : public PairChannel {
 public:
  explicit Channel(ByteStreamSource& s) : s_(s) {}
  PairPtr acquire() override {
    PairPtr p = s_.pool_.try_acquire();
    if (p) return p;
    if (s_.info_.live) {
      while (!p && s_.ring_.drop_oldest()) p = s_.pool_.try_acquire();
      if (!p) AtomicCounters::add(s_.counters_.pairs_dropped);  // the consumer holds every buffer
      return p;
    }
    return s_.pool_.acquire_until(std::chrono::steady_clock::time_point::max(), &s_.stop_);
  }
  void deliver(PairPtr pair) override {
    if (s_.ring_.push(std::move(pair), &s_.stop_)) AtomicCounters::add(s_.counters_.pairs);
  }

 private:
  ByteStreamSource& s_;
};

// Watches committed records on their way to the pairer (replay pacing follows sensor time).
class ByteStreamSource::TimingSink : public FrameSink {
 public:
  explicit TimingSink(ByteStreamSource& s) : s_(s) {}
  Frame* begin_frame(const RecordHeader& h) override {
    Frame* f = s_.pairer_->begin_frame(h);
    if (f) s_.on_record_start(f->sensor_ns);
    return f;
  }
  void commit_frame(Frame& f) override {
    s_.records_.fetch_add(1, std::memory_order_relaxed);
    s_.pairer_->commit_frame(f);
  }
  void abort_frame(Frame& f) override { s_.pairer_->abort_frame(f); }

 private:
  ByteStreamSource& s_;
};

ByteStreamSource::ByteStreamSource(SourceInfo info, StreamSettings settings)
    : info_(std::move(info)),
      pool_(settings.ring_capacity + settings.consumer_hold + 2 * settings.pairer.max_pending + 1),
      ring_(settings.ring_capacity, info_.live ? PairRing::Policy::drop_oldest : PairRing::Policy::block,
            pool_.deleter()),
      channel_(std::make_unique<Channel>(*this)),
      timing_(std::make_unique<TimingSink>(*this)),
      pairer_(std::make_unique<Pairer>(settings.pairer, *channel_, counters_)),
      parser_(std::make_unique<StreamParser>(settings.parser, *timing_, counters_)) {}

ByteStreamSource::~ByteStreamSource() {
  if (thread_.joinable()) {
    log()->error("{}: source destroyed without stop()", info_.uri);
    stop_.store(true);
    ring_.close();
    thread_.join();
  }
  // Buffers still waiting in the pairer go back before the pool is destroyed.
  pairer_->flush();
}

void ByteStreamSource::start() {
  if (started_.exchange(true)) return;
  set_state(SourceState::starting);
  try {
    open();
  } catch (const std::exception& e) {
    fail(e.what());
    ring_.close();
    throw;
  }
  thread_ = std::thread([this] { thread_main(); });
}

void ByteStreamSource::thread_main() {
  if (state() == SourceState::starting) set_state(SourceState::streaming);
  try {
    run();
  } catch (const std::exception& e) {
    log()->error("{}: capture failed: {}", info_.uri, e.what());
    end_of_stream(base::monotonic_ns());
    fail(e.what());
  }
  if (stopping() && state() != SourceState::failed)
    set_state(SourceState::stopped);
  else if (state() != SourceState::failed)
    set_state(SourceState::finished);
  ring_.close();
}

void ByteStreamSource::stop() {
  stop_.store(true, std::memory_order_seq_cst);
  interrupt();
  ring_.wake_producer();
  { std::lock_guard lock(sleep_mutex_); }
  sleep_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  const SourceState s = state();
  if (s != SourceState::finished && s != SourceState::failed) set_state(SourceState::stopped);
  ring_.close();
}

PairPtr ByteStreamSource::next(std::chrono::milliseconds timeout) {
  return ring_.pop_until(std::chrono::steady_clock::now() + timeout);
}

SourceCounters ByteStreamSource::counters() const {
  SourceCounters c = counters_.snapshot();
  c.pairs_dropped += ring_.dropped();
  return c;
}

std::optional<std::string> ByteStreamSource::error() const {
  std::lock_guard lock(error_mutex_);
  return error_;
}

bool ByteStreamSource::set_raw_tap(RawTap* tap) {
  tap_ = tap;
  return true;
}

void ByteStreamSource::feed(std::span<const std::uint8_t> bytes, std::int64_t host_ns) {
  if (tap_) tap_->on_bytes(bytes, host_ns);
  parser_->feed(bytes, host_ns);
}

void ByteStreamSource::end_of_stream(std::int64_t host_ns, bool continue_time) {
  parser_->finish(host_ns);
  pairer_->flush(continue_time);
}

bool ByteStreamSource::sleep_until(std::chrono::steady_clock::time_point deadline) {
  std::unique_lock lock(sleep_mutex_);
  return !sleep_cv_.wait_until(lock, deadline, [this] { return stopping(); });
}

void ByteStreamSource::fail(std::string message) {
  set_error(std::move(message));
  set_state(SourceState::failed);
}

void ByteStreamSource::set_error(std::string message) {
  std::lock_guard lock(error_mutex_);
  error_ = std::move(message);
}

}  // namespace naneye::driver
