// The processor's settings on their own (no recon code behind them): the config parser and its fuzz
// target link this file alone.
#include <string>

#include "naneye/app/processor.hpp"

namespace naneye::app {

const char* to_string(ReconMode m) {
  return base::enum_name(kReconModeNames, m);
}

std::string ProcessorSettings::check() const {
  const recon::BoardGeometry& board = reconstructor.corners.board;
  // BoardGeometry names its field ("rows and cols: ...", "square_mm: ..."): the keys of [board].
  if (const auto why = board.check(); !why.empty()) return "board." + why;
  if (board.count() > recon::kMaxCorners)
    return "board.rows, board.cols: at most " + std::to_string(recon::kMaxCorners) + " inner corners, got " +
           std::to_string(board.rows) + " x " + std::to_string(board.cols);
  if (!(reconstructor.reconstruction.corner_sigma_px > 0))
    return "pipeline.corner_sigma_px: must be above 0, got " +
           std::to_string(reconstructor.reconstruction.corner_sigma_px);
  if (threads != 1 && threads != 2) return "recon.threads: expected 1 or 2, got " + std::to_string(threads);
  return {};
}

}  // namespace naneye::app
