// RigReload: the processor a reload replaces is freed by whoever calls release_retired(), never by
// the worker that swapped it out (freeing maps and pools on the worker cost pairs in a SIGHUP storm);
// a prepared processor is swapped in, its name with it, unless it is of another kind.
#include "naneye/daemon/rig_reload.hpp"

#include <gtest/gtest.h>

#include <thread>

#include "naneye/recon/camera/calibration_io.hpp"

namespace naneye {
namespace {

// Records the thread that destroys it, and how often it was set to a rig.
class Probe final : public app::PairProcessor {
 public:
  Probe(std::string name, std::thread::id* freed_on, bool scene = false)
      : name_(std::move(name)), freed_on_(freed_on), scene_(scene) {}
  ~Probe() override { *freed_on_ = std::this_thread::get_id(); }
  void set_rig(const recon::StereoRig&) override { ++rigs_set; }
  void process(const driver::StereoPair&, recon::PairResult&) override {}
  bool scene() const override { return scene_; }
  bool dense() const override { return scene_; }
  std::string_view name() const override { return name_; }
  int rigs_set = 0;

 private:
  std::string name_;
  std::thread::id* freed_on_;
  bool scene_;
};

std::string processor_shown(const daemon::RigReload& reload) {
  daemon::PipelineStatus s;
  reload.fill(s);
  return s.processor;
}

std::shared_ptr<const recon::StereoRig> paper_rig() {
  return std::make_shared<const recon::StereoRig>(
      recon::load_rig({std::filesystem::path(NANEYE_SOURCE_DIR) / "config/calib/paper-d3.yaml"}));
}

TEST(RigReload, TheReplacedProcessorIsFreedByTheReleasingThreadNotTheWorker) {
  std::thread::id first_freed, second_freed, third_freed, last_freed;  // outlive every Probe
  std::unique_ptr<app::PairProcessor> processor = std::make_unique<Probe>("step", &first_freed);
  daemon::RigReload reload(paper_rig(), *processor, std::chrono::steady_clock::now());
  reload.offer(paper_rig(), std::make_unique<Probe>("step", &second_freed));

  std::thread::id worker_id;
  std::thread worker([&] {
    worker_id = std::this_thread::get_id();
    reload.apply_pending(processor);
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
    reload.apply_pending(processor);  // retires `second`
    reload.offer(paper_rig(), std::make_unique<Probe>("step", &last_freed));
    reload.apply_pending(processor);  // `third` out: the slot is taken, freed here
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

namespace naneye {
namespace {

TEST(RigReload, APreparedProcessorBringsItsNameAndOneOfAnotherKindIsNotSwappedIn) {
  std::thread::id freed[4];
  std::unique_ptr<app::PairProcessor> processor =
      std::make_unique<Probe>("board; fixed pattern removed (DSNU 0.5 DN)", &freed[0]);
  daemon::RigReload reload(paper_rig(), *processor, std::chrono::steady_clock::now());
  EXPECT_EQ(processor_shown(reload), "board; fixed pattern removed (DSNU 0.5 DN)");

  // The same kind with another pattern (a SIGHUP's): swapped in, and the status names the new one.
  reload.offer(paper_rig(), std::make_unique<Probe>("board; fixed pattern removed (DSNU 3.1 DN)", &freed[1]));
  reload.apply_pending(processor);
  EXPECT_EQ(processor->name(), "board; fixed pattern removed (DSNU 3.1 DN)");
  EXPECT_EQ(processor_shown(reload), "board; fixed pattern removed (DSNU 3.1 DN)");
  EXPECT_EQ(static_cast<Probe&>(*processor).rigs_set, 0);  // it came set to the rig
  reload.release_retired();

  // A scene processor for a pipeline whose result slots hold no scene: the one in use is set to the
  // rig instead, and keeps its name.
  reload.offer(paper_rig(), std::make_unique<Probe>("scene", &freed[2], true));
  reload.apply_pending(processor);
  EXPECT_EQ(processor->name(), "board; fixed pattern removed (DSNU 3.1 DN)");
  EXPECT_EQ(static_cast<Probe&>(*processor).rigs_set, 1);
  EXPECT_EQ(processor_shown(reload), "board; fixed pattern removed (DSNU 3.1 DN)");
  daemon::PipelineStatus s;
  reload.fill(s);
  EXPECT_EQ(s.calibration_reloads, 2u);
  EXPECT_FALSE(reload.release_retired());  // nothing was swapped out
}

}  // namespace
}  // namespace naneye
