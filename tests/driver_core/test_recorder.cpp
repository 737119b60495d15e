// The recorder when the disk fails it (issue 13): a write error ends the recording at once, with
// the summary and a file that replays every whole pair before the failure; files are 0640.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <chrono>

#include "naneye/driver/neyd.hpp"
#include "naneye/driver/recorder.hpp"
#include "naneye/driver/source_registry.hpp"
#include "stream_builder.hpp"
#include "temp_file.hpp"

namespace naneye::driver {
namespace {

using namespace std::chrono_literals;

// Sets RLIMIT_FSIZE for the test's duration: writes past it fail with EFBIG, like a full disk
// (ENOSPC) without needing a mount; SIGXFSZ is ignored so that the write just fails.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = signal(SIGXFSZ, SIG_IGN);
    rlimit r = old_;
    r.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  sighandler_t old_handler_;
};

TEST(RecorderFailures, AFullDeviceStopsTheRecordingAtOnceWithItsSummary) {
  // It kept "recording" for the whole duration on a full disk, then exited without its summary.
  test::TempFile raw("full.raw");
  raw.write(test::build(test::alternating(8)));
  auto src = make_default_registry().open("file://" + raw.str() + "?speed=realtime&loop=1");
  const auto t0 = std::chrono::steady_clock::now();
  const RecordSummary sum =
      record_to_neyd(*src, "/dev/full", RecordLimits{.pairs = std::nullopt, .seconds = 30});
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(sum.write_error.has_value());
  EXPECT_NE(sum.write_error->find("No space left on device"), std::string::npos) << *sum.write_error;
  EXPECT_NE(sum.write_error->find("/dev/full"), std::string::npos) << *sum.write_error;
  // The first flush fails (at most 50 ms of pairs at 62 per second); 30 s would be 1860.
  EXPECT_LT(sum.pairs, 31u) << "stopped after " << s << " s";
  EXPECT_FALSE(sum.error.has_value()) << "the source itself did not fail";
}

TEST(RecorderFailures, AWriteErrorLeavesAFileThatReplaysEveryWholePairBeforeIt) {
  test::TempFile raw("fsize.raw"), neyd("fsize.neyd");
  const auto recs = test::alternating(40);
  raw.write(test::build(recs));
  auto src = make_default_registry().open("file://" + raw.str() + "?speed=max&chunk=16384");
  RecordSummary sum;
  {
    // Room for ~8 of the 40 pairs (250 kB each), the cut falling inside a chunk.
    FileSizeLimit limit(2'000'000);
    sum = record_to_neyd(*src, neyd.str(), {});
  }
  ASSERT_TRUE(sum.write_error.has_value());
  EXPECT_NE(sum.write_error->find("File too large"), std::string::npos) << *sum.write_error;
  EXPECT_LT(sum.bytes, 2'000'000u);

  struct stat st {};
  ASSERT_EQ(stat(neyd.str().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
  EXPECT_LE(st.st_size, 2'000'000);

  // Every chunk on disk is whole; the reader stops at the cut with "truncated".
  {
    NeydReader reader(neyd.str());
    std::vector<std::uint8_t> chunk;
    std::int64_t t = 0;
    std::uint64_t chunks = 0;
    std::string error;
    try {
      while (reader.next(chunk, t)) ++chunks;
    } catch (const NeydError& e) {
      error = e.what();
    }
    EXPECT_NE(error.find("truncated"), std::string::npos) << error;
    EXPECT_GE(chunks, 100u) << "2 MB of 16 kB chunks";
  }
  // Replay delivers the first pairs exactly, as many as the whole chunks hold.
  auto back = make_default_registry().open("file://" + neyd.str() + "?speed=max");
  back->start();
  std::size_t k = 0;
  while (PairPtr p = back->next(2s)) {
    ASSERT_LT(2 * k + 1, recs.size());
    EXPECT_TRUE(test::frame_matches(p->left, recs[2 * k])) << k;
    EXPECT_TRUE(test::frame_matches(p->right, recs[2 * k + 1])) << k;
    ++k;
  }
  EXPECT_GE(k, 6u) << "2 MB hold 7 whole pairs of 250 kB";
  EXPECT_LE(k, 8u);
}

TEST(RecorderFailures, RecordingsAreCreatedReadableByOwnerAndGroupOnly) {
  test::TempFile raw("mode.raw"), neyd("mode.neyd");
  raw.write(test::build(test::alternating(4)));
  auto src = make_default_registry().open("file://" + raw.str() + "?speed=max");
  const mode_t old = umask(0);  // whatever the caller's umask, the file is not world-readable
  const RecordSummary sum = record_to_neyd(*src, neyd.str(), {});
  umask(old);
  EXPECT_FALSE(sum.write_error.has_value());
  struct stat st {};
  ASSERT_EQ(stat(neyd.str().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
}

}  // namespace
}  // namespace naneye::driver
