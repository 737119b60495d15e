#include "naneye/daemon/processor.hpp"

namespace naneye::daemon {

void fill_pair_identity(const driver::StereoPair& pair, recon::PairResult& out) {
  out.pair = pair.index;
  out.t_left_ns = pair.left.sensor_ns;
  out.t_right_ns = pair.right.sensor_ns;
  out.board_found = false;
  out.point_count = 0;
  out.board.reset();
  out.metrics.reset();
}

namespace {

// No detector is built into the daemon yet: a result per pair with its timestamps and no board.
class TimestampsOnly final : public PairProcessor {
 public:
  void set_rig(const recon::StereoRig&) override {}
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    fill_pair_identity(pair, out);
  }
  std::string_view name() const override { return "timestamps-only (no corner detector wired in yet)"; }
};

}  // namespace

std::unique_ptr<PairProcessor> make_processor(const Settings&) {
  return std::make_unique<TimestampsOnly>();
}

}  // namespace naneye::daemon
