// RigReload: the processor a reload replaces is freed by whoever calls release_retired(), never by
// the worker that swapped it out (freeing maps and pools on the worker cost pairs in a SIGHUP storm).
#include "naneye/daemon/rig_reload.hpp"

#include <gtest/gtest.h>

#include <thread>

#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye {
namespace {

// Records the thread that destroys it.
class Probe final : public app::PairProcessor {
 public:
  Probe(std::string name, std::thread::id* freed_on) : name_(std::move(name)), freed_on_(freed_on) {}
  ~Probe() override { *freed_on_ = std::this_thread::get_id(); }
  void set_rig(const recon::StereoRig&) override {}
  void process(const driver::StereoPair&, recon::PairResult&) override {}
  std::string_view name() const override { return name_; }

 private:
  std::string name_;
  std::thread::id* freed_on_;
};

std::shared_ptr<const recon::StereoRig> paper_rig() {
  return std::make_shared<const recon::StereoRig>(
      recon::load_rig({std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"}));
}

TEST(RigReload, TheReplacedProcessorIsFreedByTheReleasingThreadNotTheWorker) {
  daemon::RigReload reload(paper_rig(), std::chrono::steady_clock::now());
  std::thread::id first_freed, second_freed, third_freed, last_freed;  // outlive every Probe
  std::unique_ptr<app::PairProcessor> processor = std::make_unique<Probe>("step", &first_freed);
  reload.offer(paper_rig(), std::make_unique<Probe>("step", &second_freed));

  std::thread::id worker_id;
  std::thread worker([&] {
    worker_id = std::this_thread::get_id();
    reload.apply_pending(processor, "step");
  });
  worker.join();
  daemon::PipelineStatus status;
  reload.fill(status);
  EXPECT_EQ(status.calibration_reloads, 1u);
  EXPECT_EQ(first_freed, std::thread::id());  // swapped out, not yet freed

  ASSERT_TRUE(reload.release_retired());
  EXPECT_EQ(first_freed, std::this_thread::get_id());
  EXPECT_FALSE(reload.release_retired());  // one processor, freed once

  // Two swaps before a release: the slot keeps the first, the worker frees the second itself.
  reload.offer(paper_rig(), std::make_unique<Probe>("step", &third_freed));
  std::thread w2([&] {
    reload.apply_pending(processor, "step");  // retires `second`
    reload.offer(paper_rig(), std::make_unique<Probe>("step", &last_freed));
    reload.apply_pending(processor, "step");  // `third` out: the slot is taken, freed here
    worker_id = std::this_thread::get_id();
  });
  w2.join();
  EXPECT_EQ(third_freed, worker_id);
  EXPECT_EQ(second_freed, std::thread::id());
  ASSERT_TRUE(reload.release_retired());
  EXPECT_EQ(second_freed, std::this_thread::get_id());
}

}  // namespace
}  // namespace naneye
