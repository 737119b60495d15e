// v4l2:// capture loop: dequeue, unpack into a pooled pair, hand over; on device loss close
// everything and reopen with base::Backoff until the node is back (as ustreamer does).
#include "naneye/driver/v4l2_source.hpp"

#include <linux/videodev2.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <thread>

#include "log.hpp"
#include "naneye/base/clock.hpp"
#include "naneye/driver/counters.hpp"
#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/pair_ring.hpp"
#include "v4l2_device.hpp"
#include "v4l2_unpack.hpp"

namespace naneye::driver {
namespace {

using Clock = std::chrono::steady_clock;
using v4l2_detail::Dequeued;
using v4l2_detail::V4l2Device;
using v4l2_detail::V4l2Error;

class V4l2Source final : public FrameSource {
 public:
  V4l2Source(V4l2Settings s, std::string uri)
      : s_(std::move(s)),
        uri_(std::move(uri)),
        pool_(s_.pool_size),
        ring_(s_.ring_size, PairRing::Policy::drop_oldest, pool_.deleter()),
        backoff_(s_.backoff, log(), "v4l2 " + s_.device) {}
  ~V4l2Source() override { stop(); }

  void start() override {
    if (thread_.joinable()) return;
    try {
      open_device();
    } catch (const V4l2Error& e) {
      if (!e.device_gone()) {
        {
          std::lock_guard lock(info_mutex_);
          error_ = e.what();
        }
        state_ = SourceState::failed;
        ring_.close();
        throw SourceError(e.what());
      }
      next_try_ = Clock::now() + backoff_.failed(e.what());
      state_ = SourceState::waiting_for_device;
    }
    thread_ = std::thread([this] { run(); });
  }

  void stop() override {
    if (!thread_.joinable()) return;
    stopping_ = true;
    thread_.join();
    dev_.close();
    pending_.reset();
    ring_.close();
    state_ = SourceState::stopped;
  }

  PairPtr next(std::chrono::milliseconds timeout) override { return ring_.pop_until(Clock::now() + timeout); }
  SourceState state() const override { return state_.load(); }
  SourceCounters counters() const override {
    SourceCounters c = counters_.snapshot();
    c.reconnects = backoff_.counters().recoveries;
    c.pairs_dropped += ring_.dropped();
    return c;
  }
  SourceInfo info() const override {
    std::lock_guard lock(info_mutex_);
    return {uri_, "v4l2", card_.empty() ? s_.device : s_.device + " (" + card_ + ")", true, 0.0};
  }
  std::optional<std::string> error() const override {
    std::lock_guard lock(info_mutex_);
    return error_;
  }

 private:
  void open_device() {
    dev_.open(s_.device, s_.layout, s_.format, s_.buffer_count);
    dev_.stream_on();
    {
      std::lock_guard lock(info_mutex_);
      card_ = dev_.card();
    }
    backoff_.succeeded();
    backoff_.reset();
    have_first_ = false;
    have_sequence_ = false;
    last_frame_ = Clock::now();
    state_ = SourceState::streaming;
    color_ = dev_.format() == V4l2Format::sgrbg10 ? ColorMode::bayer_grbg : s_.color;
    log()->info("v4l2: streaming {} ({}), {} {}", s_.device, dev_.card(), to_string(s_.layout),
                to_string(dev_.format()));
  }

  void run() {
    while (!stopping_) {
      if (!dev_.is_open()) {
        if (Clock::now() < next_try_) {
          std::this_thread::sleep_for(
              std::min<Clock::duration>(next_try_ - Clock::now(), std::chrono::milliseconds(20)));
          continue;
        }
        try {
          open_device();
        } catch (const V4l2Error& e) {
          next_try_ = Clock::now() + backoff_.failed(e.what());
        }
        continue;
      }
      try {
        Dequeued d;
        if (!dev_.dequeue(s_.poll_timeout, d)) {
          if (state_.load() == SourceState::streaming && Clock::now() - last_frame_ > s_.stall_timeout) {
            AtomicCounters::add(counters_.stalls);
            state_ = SourceState::stalled;
          }
          continue;
        }
        last_frame_ = Clock::now();
        if (state_.load() == SourceState::stalled) state_ = SourceState::streaming;
        handle(d);
        dev_.requeue(d.index);
      } catch (const V4l2Error& e) {
        lose_device(e);
      }
    }
  }

  void lose_device(const V4l2Error& e) {
    if (!e.device_gone()) AtomicCounters::add(counters_.transfer_errors);
    next_try_ = Clock::now() + backoff_.lost(e.what());
    dev_.close();
    pending_.reset();  // an alternate-layout eye waiting for its partner will not get one
    state_ = SourceState::waiting_for_device;
  }

  void stamp(Frame& f, Sensor eye, const Dequeued& d, std::int64_t host_ns) {
    if (!have_first_) {
      first_ns_ = d.timestamp_ns;
      have_first_ = true;
    }
    f.sensor = eye;
    f.seq = static_cast<std::uint8_t>(d.sequence);
    f.sensor_ns = d.timestamp_ns;
    f.ticks64 = static_cast<std::uint64_t>(std::max<std::int64_t>(0, d.timestamp_ns - first_ns_)) * kTickHz /
                1'000'000'000;
    f.ticks = static_cast<std::uint32_t>(f.ticks64);
    f.host_ns = host_ns;
    f.color = color_;
    // Only where the URI says this grabber carries the sensor's reference pixels
    // (`reference=check|reject`): otherwise the frame says not_checked, never passed.
    f.reference = check_reference(f.pixels.data(), kSensorSize, s_.reference);
    if (f.reference == ReferenceStatus::not_checked) AtomicCounters::add(counters_.reference_unchecked);
    if (f.reference == ReferenceStatus::failed) AtomicCounters::add(counters_.reference_failures);
  }

  // With `reference=reject`, a pair with an eye that failed the check is not delivered (the pair
  // goes back to the pool when `p` is dropped).
  bool rejected(const StereoPair& p) const {
    return s_.reference.reject &&
           (p.left.reference == ReferenceStatus::failed || p.right.reference == ReferenceStatus::failed);
  }

  void handle(const Dequeued& d) {
    const std::int64_t host_ns = base::monotonic_ns();
    AtomicCounters::add(counters_.bytes, d.bytesused);
    if (have_sequence_ && d.sequence != last_sequence_ + 1)
      AtomicCounters::add(counters_.seq_gaps, d.sequence - last_sequence_ - 1);
    have_sequence_ = true;
    last_sequence_ = d.sequence;
    if (d.error || d.bytesused < dev_.image_size()) {
      AtomicCounters::add(counters_.cut_records, s_.layout == V4l2Layout::alternate ? 1 : 2);
      return;
    }
    const std::uint8_t* img = dev_.data(d.index);
    if (s_.layout == V4l2Layout::alternate) return handle_alternate(d, img, host_ns);
    PairPtr p = acquire();
    if (!p) return;
    for (int eye = 0; eye < 2; ++eye) {
      int x0 = 0, y0 = 0;
      v4l2_detail::eye_origin(s_.layout, eye, x0, y0);
      Frame& f = eye == 0 ? p->left : p->right;
      v4l2_detail::unpack_eye(img, dev_.stride(), dev_.format(), x0, y0, f);
      stamp(f, eye == 0 ? Sensor::left : Sensor::right, d, host_ns);
    }
    AtomicCounters::add(counters_.records, 2);
    if (rejected(*p)) return;
    deliver(std::move(p));
  }

  // Consecutive buffers carry one eye each; a pair forms when the other eye follows within the
  // tolerance. The eye is the field when the driver says TOP/BOTTOM, else the sequence parity.
  void handle_alternate(const Dequeued& d, const std::uint8_t* img, std::int64_t host_ns) {
    const bool right = d.field == V4L2_FIELD_BOTTOM || (d.field != V4L2_FIELD_TOP && (d.sequence & 1));
    const Sensor eye = right ? Sensor::right : Sensor::left;
    AtomicCounters::add(counters_.records);
    if (pending_) {
      const Frame& held = pending_eye_ == Sensor::left ? pending_->left : pending_->right;
      const auto gap = std::chrono::nanoseconds(std::abs(d.timestamp_ns - held.sensor_ns));
      if (pending_eye_ != eye && gap <= s_.pair_tolerance) {
        Frame& f = right ? pending_->right : pending_->left;
        v4l2_detail::unpack_eye(img, dev_.stride(), dev_.format(), 0, 0, f);
        stamp(f, eye, d, host_ns);
        if (rejected(*pending_)) {
          pending_.reset();
          return;
        }
        deliver(std::move(pending_));
        return;
      }
      AtomicCounters::add(counters_.unpaired);  // the held eye found no partner
    } else {
      pending_ = acquire();
      if (!pending_) return;
    }
    Frame& f = right ? pending_->right : pending_->left;
    v4l2_detail::unpack_eye(img, dev_.stride(), dev_.format(), 0, 0, f);
    stamp(f, eye, d, host_ns);
    pending_eye_ = eye;
  }

  // A pooled pair; when the consumer holds them all, the oldest undelivered one is sacrificed.
  PairPtr acquire() {
    PairPtr p = pool_.try_acquire();
    if (!p && ring_.drop_oldest()) p = pool_.try_acquire();
    if (!p) AtomicCounters::add(counters_.pairs_dropped);
    return p;
  }

  void deliver(PairPtr p) {
    p->index = delivered_++;
    AtomicCounters::add(counters_.pairs);
    ring_.push(std::move(p));
  }

  V4l2Settings s_;
  std::string uri_;
  PairPool pool_;
  PairRing ring_;
  V4l2Device dev_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::atomic<SourceState> state_{SourceState::starting};
  AtomicCounters counters_;
  mutable std::mutex info_mutex_;
  std::string card_;
  std::optional<std::string> error_;
  Clock::time_point last_frame_{};
  PairPtr pending_{nullptr, PairReturn{}};
  Sensor pending_eye_ = Sensor::left;
  ColorMode color_ = ColorMode::mono;
  bool have_first_ = false, have_sequence_ = false;
  base::Backoff backoff_;         // reconnects = its recoveries
  Clock::time_point next_try_{};  // capture thread (and start(), before it runs)
  std::int64_t first_ns_ = 0;
  std::uint32_t last_sequence_ = 0;
  std::uint64_t delivered_ = 0;
};

}  // namespace

V4l2Settings v4l2_settings_from(const V4l2Uri& uri) {
  V4l2Settings s;
  s.device = uri.device;
  s.layout = uri.layout;
  s.format = uri.format;
  s.color = uri.stream.parser.color;
  s.reference = uri.stream.parser.reference;
  s.pair_tolerance = std::chrono::nanoseconds(uri.stream.pairer.tolerance_ns);
  s.ring_size = uri.stream.ring_capacity;
  s.pool_size = uri.stream.ring_capacity + uri.stream.consumer_hold + 2;
  return s;
}

std::unique_ptr<FrameSource> make_v4l2_source(V4l2Settings settings, std::string uri) {
  if (settings.buffer_count < 2) throw SourceError("v4l2: buffers must be >= 2");
  if (settings.pool_size < settings.ring_size + 2) throw SourceError("v4l2: pool must exceed the ring by 2");
  if (uri.empty()) uri = "v4l2://" + settings.device;
  return std::make_unique<V4l2Source>(std::move(settings), std::move(uri));
}

}  // namespace naneye::driver
