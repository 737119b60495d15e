#pragma once
// Lock-free publication of the pipeline's latest results to any number of readers.
//
// N preallocated slots; one writer (the reconstruction worker) fills a slot in place and publishes
// it; readers (HTTP threads) pin a slot, use it, unpin it. Nobody ever waits on anybody:
//  - the writer never writes a pinned slot nor the published one; when every other slot is pinned it
//    gets nullptr and skips the publication (counted by the caller), it never blocks;
//  - a reader pins the slot it wants and re-checks, after pinning, that the slot still holds what it
//    wanted; if the writer took it in between, the reader retries (bounded).
// Each slot carries an atomic tag (the writer's sequence number, kBusy while written). The writer
// marks a slot busy *before* looking at its pin count and a reader pins *before* reading the tag;
// with sequentially consistent operations on both sides one of them always sees the other (the
// hazard-pointer argument, Michael 2004), so a reader never reads a slot being written. Every
// access is ordered by atomics, which is what lets ThreadSanitizer check it.
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

namespace naneye::daemon {

template <typename T>
class PinnedSlots {
 public:
  static constexpr std::uint64_t kBusy = ~std::uint64_t{0};
  static constexpr std::uint64_t kEmpty = kBusy - 1;

  explicit PinnedSlots(int slots) : n_(slots < 2 ? 2 : slots), slots_(std::make_unique<Slot[]>(n_)) {}

  int size() const { return n_; }

  // Writer only, before the first publication: fn(T&) on every slot (to size buffers inside T once).
  template <typename Fn>
  void prepare(Fn&& fn) {
    for (int i = 0; i < n_; ++i) fn(slots_[i].value);
  }

  // Writer only. A slot to fill for the next publication, or nullptr when all others are pinned.
  // The slot keeps its previous contents (so a caller can reuse buffers inside T).
  T* begin_write() {
    const int cur = current_.load();
    for (int k = 1; k <= n_; ++k) {
      // Oldest first: the slot after the last one written, round robin.
      const int i = (next_ + k - 1) % n_;
      if (i == cur) continue;
      Slot& s = slots_[i];
      const std::uint64_t old = s.tag.exchange(kBusy);
      if (s.pins.load() == 0) {
        writing_ = i;
        return &s.value;
      }
      s.tag.store(old);  // a reader holds it: leave its contents intact
    }
    return nullptr;
  }

  // Writer only: makes the slot from begin_write() the latest, tagged with `seq` (increasing).
  void publish(std::uint64_t seq) {
    Slot& s = slots_[writing_];
    s.tag.store(seq);
    current_.store(writing_);
    next_ = (writing_ + 1) % n_;
  }

  // Writer only: gives back a slot from begin_write() without publishing it.
  void abandon() { slots_[writing_].tag.store(kEmpty); }

  // Calls fn(const T&, seq) on the latest publication while it is pinned. False before the first
  // publication (or, in theory, when the writer overtook the reader many times in a row).
  template <typename Fn>
  bool read_latest(Fn&& fn) const {
    for (int attempt = 0; attempt < 16; ++attempt) {
      const int i = current_.load();
      if (i < 0) return false;
      const Slot& s = slots_[i];
      s.pins.fetch_add(1);
      const std::uint64_t tag = s.tag.load();
      if (current_.load() == i && tag != kBusy && tag != kEmpty) {
        fn(s.value, tag);
        s.pins.fetch_sub(1);
        return true;
      }
      s.pins.fetch_sub(1);
    }
    return false;
  }

  // Calls fn(const T&) on the slot tagged `seq` if it is still held; false when it is gone.
  template <typename Fn>
  bool read_seq(std::uint64_t seq, Fn&& fn) const {
    for (int i = 0; i < n_; ++i) {
      const Slot& s = slots_[i];
      if (s.tag.load() != seq) continue;
      s.pins.fetch_add(1);
      const bool still = s.tag.load() == seq;
      if (still) fn(s.value);
      s.pins.fetch_sub(1);
      if (still) return true;
    }
    return false;
  }

  // The newest and oldest sequence numbers held (any reader): empty before the first publication.
  std::optional<std::uint64_t> latest_seq() const {
    const int i = current_.load();
    if (i < 0) return std::nullopt;
    const std::uint64_t t = slots_[i].tag.load();
    if (t == kBusy || t == kEmpty) return std::nullopt;
    return t;
  }

 private:
  struct Slot {
    T value{};
    mutable std::atomic<int> pins{0};
    std::atomic<std::uint64_t> tag{kEmpty};
  };
  int n_;
  std::unique_ptr<Slot[]> slots_;
  std::atomic<int> current_{-1};
  int writing_ = 0;  // writer-only state
  int next_ = 0;
};

}  // namespace naneye::daemon
