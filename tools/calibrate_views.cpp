// Board views for `naneye calibrate`: every pair of every input, the board detected in each eye by a
// full search (views are independent: no tracking), both eyes' numbering made to agree.
#include "calibrate_views.hpp"

#include <unistd.h>

#include <spdlog/spdlog.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "cli_inputs.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/app/sources.hpp"
#include "naneye/recon/corners/stereo_ids.hpp"
#include "source_pairs.hpp"

namespace naneye::tools {

Progress::Progress(int log_every) : tty_(::isatty(STDERR_FILENO) == 1), log_every_(log_every) {}

Progress::~Progress() {
  if (open_) std::fputs("\n", stderr);
}

void Progress::update(const std::string& text, bool force_log) {
  if (tty_) {
    std::fprintf(stderr, "\r\033[K%s", text.c_str());
    std::fflush(stderr);
    open_ = true;
  } else if (force_log || ++count_ % log_every_ == 0) {
    spdlog::info("{}", text);
  }
}

void Progress::update(double fraction, const std::string& text, bool force_log) {
  constexpr int kWidth = 24;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const int filled = static_cast<int>(fraction * kWidth + 0.5);
  char head[64];
  std::snprintf(head, sizeof head, "[%s%s] %3d %% ",
                std::string(static_cast<std::size_t>(filled), '#').c_str(),
                std::string(static_cast<std::size_t>(kWidth - filled), '.').c_str(),
                static_cast<int>(fraction * 100 + 0.5));
  update(head + text, force_log);
}

void Progress::done(const std::string& text) {
  if (tty_) {
    std::fprintf(stderr, "\r\033[K%s\n", text.c_str());
    open_ = false;
  } else {
    spdlog::info("{}", text);
  }
}

std::vector<InputUri> expand_input(const std::string& input) {
  std::vector<InputUri> uris;
  const bool is_uri = input.find("://") != std::string::npos;
  if (!is_uri && std::filesystem::is_directory(input)) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(input)) {
      const auto ext = e.path().extension();
      if (e.is_regular_file() && (ext == ".raw" || ext == ".neyd")) files.push_back(e.path());
    }
    if (files.empty()) throw std::runtime_error(input + ": folder holds no .raw or .neyd capture");
    std::sort(files.begin(), files.end());
    for (const auto& f : files) uris.push_back({"file://" + f.string() + "?speed=max", f.string()});
    return uris;
  }
  if (!is_uri && !std::filesystem::exists(input))
    throw std::runtime_error(input + ": no such file or folder");
  uris.push_back({lossless_input_uri(input), input});
  return uris;
}

std::vector<recon::BoardCorner> corners_of(const recon::CornerResult& r) {
  std::vector<recon::BoardCorner> out;
  for (int i = 0; i < r.count; ++i) {
    const auto& c = r.corners[static_cast<std::size_t>(i)];
    out.push_back({c.row, c.col, c.px});
  }
  return out;
}

CollectedViews collect_views(const std::vector<std::string>& inputs, const recon::StereoRig& guess,
                             const recon::CornerSettings& corners, long long max_pairs, Progress& progress) {
  CollectedViews out;
  recon::CornerDetector detect_left(guess.left, corners), detect_right(guess.right, corners);
  recon::CornerResult left, right;
  const auto registry = app::make_source_registry();
  std::vector<InputUri> uris;
  for (const std::string& input : inputs)
    for (auto& u : expand_input(input)) uris.push_back(std::move(u));
  std::size_t uris_done = 0;
  for (const auto& [uri, label] : uris) {
    std::unique_ptr<driver::FrameSource> source;
    try {
      source = registry.open(uri);
      source->start();
    } catch (const std::exception& e) {
      throw std::runtime_error(uri + ": cannot be read: " + e.what());
    }
    unsigned long long index = 0;
    for_each_pair(*source, max_pairs <= 0 ? -1 : max_pairs, [&](driver::StereoPair& pair) {
      ++out.pairs;
      const bool l = detect_left.detect_full(app::image_view(pair.left), left);
      const bool r = detect_right.detect_full(app::image_view(pair.right), right);
      if (l || r) {
        recon::CalibrationView v;
        if (l) v.left = corners_of(left);
        if (r) {
          bool keep = true;
          if (l) {
            const auto check = recon::resolve_stereo_ids(guess, left, right);
            keep = check.status == recon::StereoIdStatus::consistent ||
                   check.status == recon::StereoIdStatus::flipped_right;
            out.ambiguous += !keep;
          }
          if (keep) v.right = corners_of(right);
        }
        out.one_eye += v.left.empty() || v.right.empty();
        out.views.push_back(std::move(v));
        out.sources.push_back({label, index});
      } else {
        ++out.no_board;
      }
      ++index;
      // The bar moves per input (a folder of dumps, several --input); within one input only
      // when --max-pairs bounds it (a stream does not announce its length).
      const double within = max_pairs > 0 ? static_cast<double>(index) / static_cast<double>(max_pairs) : 0.0;
      progress.update((static_cast<double>(uris_done) + within) / static_cast<double>(uris.size()),
                      "detecting boards: " + std::to_string(out.pairs) + " pairs read, " +
                          std::to_string(out.views.size()) + " boards found");
    });
    source->stop();
    if (auto err = source->error()) throw std::runtime_error(uri + ": cannot be read: " + *err);
    if (index == 0) throw std::runtime_error(uri + ": no stereo pair could be read");
    ++uris_done;
  }
  progress.done("detected boards: " + std::to_string(out.views.size()) + " views in " +
                std::to_string(out.pairs) + " pairs (" + std::to_string(out.no_board) +
                " skipped without a full board in either eye)");
  return out;
}

}  // namespace naneye::tools
