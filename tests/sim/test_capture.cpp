// Captures on disk: repeatable to the byte, parsed and paired by the real driver, truth exact.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "naneye/driver/source_registry.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/sim/capture.hpp"

namespace naneye::sim {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() /
           ("naneye-sim-" + std::to_string(::getpid()) + "-" + std::to_string(counter()++));
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  static int& counter() {
    static int n = 0;
    return n;
  }
};

std::vector<char> bytes_of(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), {}};
}

nlohmann::json truth_of(const fs::path& dir) {
  std::ifstream f(dir / "truth.json");
  return nlohmann::json::parse(f);
}

// Pairs belong to the source's pool: the test keeps copies.
std::vector<std::unique_ptr<driver::StereoPair>> replay(const fs::path& file,
                                                        driver::SourceCounters* counters = nullptr) {
  const driver::SourceRegistry reg = driver::make_default_registry();
  auto src = reg.open("file://" + file.string() + "?speed=max");
  src->start();
  std::vector<std::unique_ptr<driver::StereoPair>> pairs;
  while (auto p = src->next(std::chrono::milliseconds(5000)))
    pairs.push_back(std::make_unique<driver::StereoPair>(*p));
  if (counters) *counters = src->counters();
  src->stop();
  return pairs;
}

CaptureSettings small(const fs::path& dir, int pairs, std::uint64_t seed) {
  CaptureSettings o;
  o.preset = "paper-d3";
  o.calibration = fs::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml";
  o.pairs = pairs;
  o.seed = seed;
  o.out_dir = dir;
  o.supersample = 4;  // these tests check bytes, times and truth, not edge accuracy: keep them quick
  return o;
}

TEST(Capture, SameSeedGivesTheSameBytes) {
  TempDir a, b, c;
  write_capture(small(a.path, 2, 5));
  write_capture(small(b.path, 2, 5));
  write_capture(small(c.path, 2, 6));
  const auto ra = bytes_of(a.path / "capture.raw");
  EXPECT_EQ(ra.size(), 4 * driver::kRecordSize);
  EXPECT_EQ(ra, bytes_of(b.path / "capture.raw"));
  EXPECT_EQ(bytes_of(a.path / "truth.json"), bytes_of(b.path / "truth.json"));
  EXPECT_NE(ra, bytes_of(c.path / "capture.raw"));
}

TEST(Capture, DriverParsesAndPairsItAsTheTruthSays) {
  TempDir d;
  CaptureSettings o = small(d.path, 6, 9);
  // Start just before the 32-bit tick counter wraps: pairing must extend time across it.
  o.start_ticks = (std::int64_t{1} << 32) - 48'000'000 / 20;
  write_capture(o);
  const nlohmann::json truth = truth_of(d.path);
  driver::SourceCounters c;
  const auto pairs = replay(d.path / "capture.raw", &c);
  ASSERT_EQ(pairs.size(), 6u);
  EXPECT_EQ(c.records, 12u);
  EXPECT_EQ(c.sync_losses + c.seq_gaps + c.cut_records + c.reference_failures + c.unpaired, 0u);
  const std::int64_t t0 = pairs[0]->left.sensor_ns;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const auto& t = truth["pairs"][i];
    // Truth times are ns since the first record, rounded; the driver's come from the same ticks.
    EXPECT_NEAR(pairs[i]->left.sensor_ns - t0, t["t_left_ns"].get<double>(), 1.0);
    EXPECT_NEAR(pairs[i]->offset_ns(), t["t_right_ns"].get<double>() - t["t_left_ns"].get<double>(), 2.0);
    EXPECT_GT(pairs[i]->offset_ns(), 0);
    EXPECT_EQ(pairs[i]->left.reference, naneye::driver::ReferenceStatus::passed);
    EXPECT_EQ(pairs[i]->right.reference, naneye::driver::ReferenceStatus::passed);
    EXPECT_EQ(pairs[i]->left.ticks, t["t_left_ticks"].get<std::uint32_t>());
  }
  // The frame period stays inside the sensors' 43-62 fps.
  for (std::size_t i = 1; i < pairs.size(); ++i) {
    const double period_ms =
        1e-6 * static_cast<double>(pairs[i]->left.sensor_ns - pairs[i - 1]->left.sensor_ns);
    EXPECT_GE(period_ms, 1000.0 / 62.0 - 1e-6);
    EXPECT_LE(period_ms, 1000.0 / 43.0 + 1e-6);
  }
  EXPECT_GT(pairs[0]->left.ticks, pairs[5]->left.ticks) << "expected the tick counter to wrap";
}

TEST(Capture, FreeRunningClocksDriftWithinTheSensorsRange) {
  Rng rng(21);
  FrameClock clock(TimingSettings{}, 0, rng);
  PairTime prev = clock.next(rng);
  double lo = 1e9, hi = 0, lag_lo = 1e9, lag_hi = 0;
  for (int i = 0; i < 3000; ++i) {  // one minute of frames
    const PairTime t = clock.next(rng);
    const double fps =
        static_cast<double>(driver::kTickHz) / static_cast<double>(t.left_ticks - prev.left_ticks);
    const double lag_ms = 1e3 * static_cast<double>(t.right_ticks - t.left_ticks) / driver::kTickHz;
    lo = std::min(lo, fps), hi = std::max(hi, fps);
    lag_lo = std::min(lag_lo, lag_ms), lag_hi = std::max(lag_hi, lag_ms);
    ASSERT_LT(lag_ms, 0.5e3 / fps);  // under half a period: pairing by nearest timestamp is unambiguous
    prev = t;
  }
  EXPECT_GE(lo, 43.0 - 1e-3);
  EXPECT_LE(hi, 62.0 + 1e-3);
  EXPECT_GT(hi - lo, 3.0);  // it does drift
  EXPECT_GE(lag_lo, 0.5 - 1e-3);
  EXPECT_GT(lag_hi - lag_lo, 0.3);
}

TEST(Capture, NeydHoldsTheSamePairsAsRaw) {
  TempDir r, n;
  CaptureSettings o = small(r.path, 3, 4);
  write_capture(o);
  o.out_dir = n.path;
  o.format = CaptureFormat::neyd;
  write_capture(o);
  const auto a = replay(r.path / "capture.raw"), b = replay(n.path / "capture.neyd");
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i]->left.pixels, b[i]->left.pixels);
    EXPECT_EQ(a[i]->right.pixels, b[i]->right.pixels);
    EXPECT_EQ(a[i]->offset_ns(), b[i]->offset_ns());
  }
}

TEST(Capture, TruthAgreesWithTheCameraModel) {
  TempDir d;
  CaptureSettings o = small(d.path, 10, 3);
  o.partial_share = 0.3;
  o.absent_share = 0.1;
  write_capture(o);
  const nlohmann::json truth = truth_of(d.path);
  const recon::StereoRig rig = recon::load_rig(o.calibration);
  EXPECT_EQ(truth["pattern"], nlohmann::json({6, 8}));
  EXPECT_DOUBLE_EQ(truth["square_mm"].get<double>(), 5.99);
  BoardGeometry board;
  int in_view = 0;
  for (const auto& p : truth["pairs"]) {
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R(r, c) = p["board_rotation"][r][c].get<double>();
    const Eigen::Vector3d t(p["board_translation_mm"][0].get<double>(),
                            p["board_translation_mm"][1].get<double>(),
                            p["board_translation_mm"][2].get<double>());
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    ASSERT_EQ(p["corners_xyz_mm"].size(), 48u);
    bool all = p["board_present"].get<bool>();
    for (int k = 0; k < 48; ++k) {
      const Eigen::Vector3d X(p["corners_xyz_mm"][k][0].get<double>(),
                              p["corners_xyz_mm"][k][1].get<double>(),
                              p["corners_xyz_mm"][k][2].get<double>());
      EXPECT_LT((X - (R * board.corner(k) + t)).norm(), 1e-9);
      if (!p["left_px"][k].is_null()) {
        const Eigen::Vector2d px(p["left_px"][k][0].get<double>(), p["left_px"][k][1].get<double>());
        EXPECT_LT((px - rig.left.project(X)).norm(), 1e-9);
      }
      if (!p["right_px"][k].is_null()) {
        const Eigen::Vector2d px(p["right_px"][k][0].get<double>(), p["right_px"][k][1].get<double>());
        EXPECT_LT((px - rig.right.project(rig.R * X + rig.T)).norm(), 1e-9);
      }
      all = all && p["left_in_view"][k].get<bool>() && p["right_in_view"][k].get<bool>();
    }
    EXPECT_EQ(p["board_in_view"].get<bool>(), all);
    in_view += all;
  }
  EXPECT_GE(in_view, 3);   // most pairs show the whole board ...
  EXPECT_LT(in_view, 10);  // ... but not all, with these shares
}

TEST(Capture, FaultsShowUpInTheDriverCounters) {
  TempDir d;
  CaptureSettings o = small(d.path, 8, 12);
  o.faults.lost_record_rate = 0.25;
  o.faults.truncate_tail = 1000;
  write_capture(o);
  const nlohmann::json truth = truth_of(d.path);
  int lost = 0;
  for (const auto& p : truth["pairs"]) lost += p["left_lost"].get<bool>() + p["right_lost"].get<bool>();
  ASSERT_GT(lost, 0);
  driver::SourceCounters c;
  replay(d.path / "capture.raw", &c);
  EXPECT_EQ(c.cut_records, 1u);  // the truncated last record
  EXPECT_EQ(c.records, 16u - lost - 1);
  // Losses inside the stream are seq gaps; losses at the very start or end cannot be seen.
  EXPECT_LE(c.seq_gaps, static_cast<std::uint64_t>(lost));
  EXPECT_GE(c.seq_gaps, 1u);
}

TEST(Capture, BitFlipsAndDroppedBytesAreSurvivedAndCounted) {
  TempDir d;
  CaptureSettings o = small(d.path, 10, 2);
  o.faults.dropped_byte_rate = 1e-6;  // about one record in eight loses a byte ...
  o.faults.bit_flip_rate = 1e-6;      // ... and one in eight gets a flipped bit
  write_capture(o);
  const nlohmann::json truth = truth_of(d.path);
  int damaged = 0;
  for (const auto& p : truth["pairs"]) damaged += p["damaged_bytes"].get<int>() > 0;
  ASSERT_GT(damaged, 0) << "this seed damages some records";
  ASSERT_LT(damaged, 10);
  driver::SourceCounters c;
  const auto pairs = replay(d.path / "capture.raw", &c);
  EXPECT_LT(c.bytes, 20 * driver::kRecordSize + 1);
  // A damaged pair costs at most itself and the resynchronisation on the next record.
  EXPECT_GE(pairs.size(), static_cast<std::size_t>(10 - 2 * damaged));
  EXPECT_LT(pairs.size(), 11u);
}

}  // namespace
}  // namespace naneye::sim
