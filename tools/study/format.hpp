#pragma once
// Numbers as the study's report prints them: fixed decimals, scientific for tiny or huge values
// (the division lambdas, ~1e-6 px^-2), "-" for a figure that does not exist.
#include <string>

#include "paper_tables.hpp"
#include "study.hpp"

namespace naneye::tools::study {

std::string num(double v, int decimals = 3);
// "P / D / R" of one row.
std::string pdr(double P, double D, double R);
std::string pdr(const Scores& s);
std::string pdr(const paper::PDR& p);

}  // namespace naneye::tools::study
