// Recording a source that has no raw bytes (as a simulator): pairs are re-encoded with
// encode_record, and the replay gives back the same frames.
#include <gtest/gtest.h>

#include <deque>

#include "naneye/driver/pair_pool.hpp"
#include "naneye/driver/recorder.hpp"
#include "naneye/driver/source_registry.hpp"
#include "stream_builder.hpp"
#include "temp_file.hpp"

namespace naneye::driver {
namespace {

using namespace std::chrono_literals;

// Hands out prepared pairs, then finishes; no raw tap (the FrameSource default).
class PairListSource : public FrameSource {
 public:
  explicit PairListSource(const std::vector<test::RecordSpec>& recs) {
    for (std::size_t k = 0; k + 1 < recs.size(); k += 2) specs_.emplace_back(recs[k], recs[k + 1]);
  }
  void start() override { state_ = SourceState::streaming; }
  void stop() override {
    if (state_ != SourceState::finished) state_ = SourceState::stopped;
  }
  PairPtr next(std::chrono::milliseconds) override {
    if (specs_.empty()) {
      state_ = SourceState::finished;
      return PairPtr(nullptr, pool_.deleter());
    }
    PairPtr p = pool_.try_acquire();
    const auto [l, r] = specs_.front();
    specs_.pop_front();
    fill(p->left, l);
    fill(p->right, r);
    p->index = index_++;
    return p;
  }
  SourceState state() const override { return state_; }
  SourceCounters counters() const override { return {}; }
  SourceInfo info() const override { return {"test://pairs", "test", "list", false, 0}; }
  std::optional<std::string> error() const override { return std::nullopt; }

 private:
  static void fill(Frame& f, const test::RecordSpec& r) {
    f.seq = r.seq;
    f.sensor = r.sensor;
    f.ticks = r.ticks;
    f.sensor_ns = static_cast<std::int64_t>(r.ticks) * 125 / 6;
    for (std::size_t i = 0; i < kPixelCount; ++i) f.pixels[i] = test::pixel_value(r, kSensorSize, i);
  }
  PairPool pool_{2};
  std::deque<std::pair<test::RecordSpec, test::RecordSpec>> specs_;
  std::uint64_t index_ = 0;
  SourceState state_ = SourceState::starting;
};

TEST(Recorder, SourcesWithoutRawBytesAreReEncoded) {
  test::TempFile neyd("reencode.neyd");
  // In the second pair the right record came first (seq 12, left 13): records go out in seq order.
  auto recs = test::alternating(5, 10, 5000, 1'089'600, 200'000);
  std::swap(recs[2].seq, recs[3].seq);
  recs[3].ticks = recs[2].ticks - 100'000;
  PairListSource src(recs);
  const RecordSummary sum = record_to_neyd(src, neyd.str(), {});
  EXPECT_FALSE(sum.raw);
  EXPECT_EQ(sum.pairs, 5u);
  EXPECT_EQ(sum.chunks, 5u);
  EXPECT_EQ(sum.bytes, 10 * kRecordSize);
  auto back = make_default_registry().open("file://" + neyd.str() + "?speed=max");
  back->start();
  std::vector<std::pair<Frame, Frame>> got;
  while (PairPtr p = back->next(2s)) got.emplace_back(p->left, p->right);
  const SourceCounters c = back->counters();
  EXPECT_EQ(c.records, 10u);
  EXPECT_EQ(c.pairs, 5u);
  EXPECT_EQ(c.unpaired, 0u);
  EXPECT_EQ(c.seq_gaps, 0u);
  EXPECT_EQ(c.sync_losses, 0u);
  ASSERT_EQ(got.size(), 5u);
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_TRUE(test::frame_matches(got[k].first, recs[2 * k])) << k;
    EXPECT_TRUE(test::frame_matches(got[k].second, recs[2 * k + 1])) << k;
  }
}

}  // namespace
}  // namespace naneye::driver
