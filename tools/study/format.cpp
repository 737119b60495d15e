#include "format.hpp"

#include <cmath>
#include <cstdio>

namespace naneye::tools::study {

std::string num(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[48];
  if (std::abs(v) >= 1e5 || (v != 0 && std::abs(v) < 1e-3))
    std::snprintf(buf, sizeof buf, "%.2e", v);
  else
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string pdr(double P, double D, double R) {
  return num(P) + " / " + num(D) + " / " + num(R);
}
std::string pdr(const Scores& s) {
  return pdr(s.P, s.D, s.R);
}
std::string pdr(const paper::PDR& p) {
  return pdr(p.P, p.D, p.R);
}

}  // namespace naneye::tools::study
