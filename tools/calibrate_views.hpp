#pragma once
// `naneye calibrate`'s two halves: collecting board views from the inputs (calibrate_views.cpp) and
// printing the report (calibrate_report.cpp).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "naneye/recon/calibrate/calibrate.hpp"
#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/corners/detector.hpp"

namespace naneye::tools {

// A one-line progress display on stderr: redrawn in place on a terminal, a log line every
// `log_every` updates otherwise (so logs of a redirected run stay readable).
class Progress {
 public:
  explicit Progress(int log_every = 50);
  ~Progress();
  void update(const std::string& text, bool force_log = false);
  // The same with a bar: fraction of the whole job done, 0..1 ("[#######.......]  42 % text").
  void update(double fraction, const std::string& text, bool force_log = false);
  void done(const std::string& text);  // ends the line (terminal) or logs it
  bool tty() const { return tty_; }

 private:
  bool tty_ = false;
  bool open_ = false;
  int count_ = 0, log_every_ = 50;
};

// Where a view came from, for the report.
struct ViewSource {
  std::string input;        // the URI as given
  unsigned long long pair;  // index in that input
};

struct CollectedViews {
  std::vector<recon::CalibrationView> views;
  std::vector<ViewSource> sources;
  long long pairs = 0;      // pairs read over all inputs
  long long no_board = 0;   // pairs where neither eye showed the full board (skipped)
  long long one_eye = 0;    // views with the board in one eye only (kept)
  long long ambiguous = 0;  // both eyes, but the numbering could not be matched: left kept
};

// The source URIs behind one --input: a folder becomes one file:// URI per .raw / .neyd file in it
// (sorted); a plain path or a file:// URI without a speed replays at max speed. `label` is what the
// report shows: the input as given, or the file found in the folder.
struct InputUri {
  std::string uri, label;
};
std::vector<InputUri> expand_input(const std::string& input);

// One eye's detected corners as the calibration takes them (grid position and pixel).
std::vector<recon::BoardCorner> corners_of(const recon::CornerResult& r);

// Reads every pair of every input and detects the board in each eye with a full search (views are
// independent). `guess` models the lenses for the detector. Throws std::runtime_error naming an
// unreadable input.
CollectedViews collect_views(const std::vector<std::string>& inputs, const recon::StereoRig& guess,
                             const recon::CornerSettings& corners, long long max_pairs, Progress& progress);

struct ReportOptions {
  bool json = false;
  std::string output;
};

// The report of a calibration: text (stdout) or one JSON object.
void print_report(const recon::CalibrationResult& res, const CollectedViews& views,
                  const recon::SplitValidation* splits, const recon::OddEvenValidation* odd_even,
                  const recon::CalibrationSettings& settings, const ReportOptions& o);
nlohmann::json report_json(const recon::CalibrationResult& res, const CollectedViews& views,
                           const recon::SplitValidation* splits, const recon::OddEvenValidation* odd_even);

}  // namespace naneye::tools
