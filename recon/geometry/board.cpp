#include "naneye/recon/geometry/board.hpp"

#include <cmath>

namespace naneye::recon {

std::string BoardGeometry::check() const {
  if (rows < 2 || cols < 2)
    return "rows and cols: at least 2 x 2 inner corners, got " + std::to_string(rows) + " x " +
           std::to_string(cols);
  if (!std::isfinite(square_mm) || square_mm <= 0)
    return "square_mm: a finite size above 0 mm, got " + std::to_string(square_mm);
  return {};
}

}  // namespace naneye::recon
