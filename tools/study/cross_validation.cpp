// The paper's "Evaluation Based on Cross-Validation" tables. They need calibration from rendered views
// (the `calib` work, recon/calibrate.hpp), which this branch does not have yet.
#include "study.hpp"

namespace naneye::tools::study {

std::string cross_validation_section(const StudyRun&) {
  return "## Cross-validation (paper Tables \"Results for the baseline model\" and following)\n\n"
         "Not yet: it needs naneye's own calibration from the rendered views (calibrate on 10, evaluate on "
         "the other 9, three splits, and an odd/even split), which is not part of this build.\n\n";
}

}  // namespace naneye::tools::study
