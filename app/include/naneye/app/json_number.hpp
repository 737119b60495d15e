#pragma once
// One rule for every figure naneye serialises: a number only where there is one to stand behind;
// NaN or infinity (no depth, no covariance, no median) goes out as null, never as a made-up value.
#include <cmath>
#include <nlohmann/json.hpp>

namespace naneye::app {

inline nlohmann::json finite_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace naneye::app
