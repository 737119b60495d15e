// `naneye record SOURCE_URI -o FILE.neyd [--frames N | --seconds S]` and
// `naneye replay FILE [--stats] [--json]`: capture to the .neyd container, and look at what the
// parser makes of a capture (records, pairs, rates, left/right offsets, every counter).
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>

#include "commands.hpp"
#include "naneye/app/sources.hpp"
#include "naneye/driver/recorder.hpp"
#include "source_pairs.hpp"

namespace naneye::tools {
namespace {

using driver::SourceCounters;

nlohmann::json counters_json(const SourceCounters& c) {
  nlohmann::json j = nlohmann::json::object();
  for_each_counter(c, [&j](const char* name, const char*, std::uint64_t v) { j[name] = v; });
  return j;
}

// Ctrl-C / SIGTERM end a recording cleanly: the signals are blocked in every thread and a watcher
// turns them into a flag (no global state, no async-signal-unsafe handler).
class SignalWatch {
 public:
  SignalWatch() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, &old_);
    thread_ = std::thread([this] {
      const timespec tick{0, 100'000'000};
      while (!done_.load())
        if (sigtimedwait(&set_, nullptr, &tick) > 0) interrupted.store(true);
    });
  }
  ~SignalWatch() {
    done_.store(true);
    thread_.join();
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  std::atomic<bool> interrupted{false};

 private:
  sigset_t set_{}, old_{};
  std::atomic<bool> done_{false};
  std::thread thread_;
};

struct RecordOptions {
  std::string uri, output;
  std::optional<std::uint64_t> frames;
  std::optional<double> seconds;
};

void run_record(const RecordOptions& o) {
  auto registry = app::make_source_registry();
  auto source = registry.open(o.uri);
  SignalWatch signals;  // before start(): the capture thread inherits the blocked mask
  const driver::RecordSummary s = driver::record_to_neyd(
      *source, o.output, driver::RecordLimits{o.frames, o.seconds}, &signals.interrupted);
  nlohmann::json j = {{"output", o.output},
                      {"pairs", s.pairs},
                      {"chunks", s.chunks},
                      {"bytes", s.bytes},
                      {"bytes_as_received", s.raw},
                      {"source_state", driver::to_string(s.end_state)},
                      {"counters", counters_json(s.counters)}};
  if (s.error) j["error"] = *s.error;
  if (s.write_error) j["write_error"] = *s.write_error;
  std::cout << j.dump(2) << "\n";
  if (s.write_error) {
    throw driver::SourceError("recording stopped: " + *s.write_error + "; " + o.output +
                              " holds the pairs up to the failure (no end marker)");
  }
  if (s.error) throw driver::SourceError(*s.error);
}

struct Series {
  std::uint64_t n = 0;
  std::int64_t first = 0, last = 0;
  void add(std::int64_t t) {
    if (n++ == 0) first = t;
    last = t;
  }
  double fps() const {
    return n > 1 && last > first ? static_cast<double>(n - 1) * 1e9 / static_cast<double>(last - first) : 0;
  }
};

struct ReplayOptions {
  std::string file;
  bool stats = false, json = false;
};

void run_replay(const ReplayOptions& o) {
  // A plain path replays as fast as possible, losslessly; a URI keeps its own parameters.
  const std::string uri =
      o.file.find("://") == std::string::npos ? "file://" + o.file + "?speed=max" : o.file;
  auto source = app::make_source_registry().open(uri);
  source->start();
  Series left, right;
  double off_sum = 0;
  std::int64_t off_min = std::numeric_limits<std::int64_t>::max(),
               off_max = std::numeric_limits<std::int64_t>::min();
  std::uint64_t ref_bad = 0;
  const auto pairs = static_cast<std::uint64_t>(for_each_pair(*source, -1, [&](driver::StereoPair& pair) {
    left.add(pair.left.sensor_ns);
    right.add(pair.right.sensor_ns);
    const std::int64_t off = pair.offset_ns();
    off_sum += static_cast<double>(off);
    off_min = std::min(off_min, off);
    off_max = std::max(off_max, off);
    ref_bad += (pair.left.reference == driver::ReferenceStatus::failed) +
               (pair.right.reference == driver::ReferenceStatus::failed);
    if (!o.stats && !o.json)
      std::cout << "pair " << pair.index << "  left seq " << int(pair.left.seq) << " t "
                << pair.left.sensor_ns / 1e6 << " ms  right seq " << int(pair.right.seq) << " t "
                << pair.right.sensor_ns / 1e6 << " ms  offset " << off / 1e6 << " ms\n";
  }));
  source->stop();
  const SourceCounters c = source->counters();
  const auto err = source->error();
  const auto ms = [](double ns) { return ns / 1e6; };
  nlohmann::json j = {{"source", uri},
                      {"state", driver::to_string(source->state())},
                      {"records", c.records},
                      {"pairs", pairs},
                      {"fps_left", left.fps()},
                      {"fps_right", right.fps()},
                      {"duration_s", pairs > 1 ? static_cast<double>(left.last - left.first) / 1e9 : 0.0},
                      {"offset_ms", pairs ? nlohmann::json{{"min", ms(static_cast<double>(off_min))},
                                                           {"mean", ms(off_sum / static_cast<double>(pairs))},
                                                           {"max", ms(static_cast<double>(off_max))}}
                                          : nlohmann::json(nullptr)},
                      {"frames_failing_reference", ref_bad},
                      {"counters", counters_json(c)},
                      {"error", err ? nlohmann::json(*err) : nlohmann::json(nullptr)}};
  if (o.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "source        " << uri << " (" << j["state"].get<std::string>() << ")\n"
              << "records       " << c.records << "\n"
              << "pairs         " << pairs << "\n"
              << "fps           left " << left.fps() << "  right " << right.fps() << "\n";
    if (pairs)
      std::cout << "offset ms     min " << ms(static_cast<double>(off_min)) << "  mean "
                << ms(off_sum / static_cast<double>(pairs)) << "  max " << ms(static_cast<double>(off_max))
                << "\n";
    std::cout << "counters\n";
    for (const auto& [k, v] : j["counters"].items())
      std::cout << "  " << k << std::string(20 - k.size(), ' ') << v << "\n";
    if (err) std::cout << "error         " << *err << "\n";
  }
  if (err) throw driver::SourceError(*err);
  // An empty file or one of random bytes is not a capture: said, and a failure for scripts.
  if (pairs == 0) {
    throw driver::SourceError(uri + ": no complete stereo pair (" + std::to_string(c.records) +
                              " records): empty, or not a NanEye capture");
  }
}

}  // namespace

void add_driver_commands(CLI::App& app) {
  auto rec = std::make_shared<RecordOptions>();
  auto* r =
      app.add_subcommand("record", "Record any source (usb://, v4l2://, file://, ...) into a .neyd capture");
  r->add_option("source", rec->uri, "Source URI, e.g. usb://10f8:c487 or file:///x.raw")->required();
  r->add_option("-o,--output", rec->output, "The .neyd file to write")->required();
  auto* frames = r->add_option("--frames", rec->frames, "Stop after N pairs")->check(CLI::PositiveNumber);
  auto* secs = r->add_option("--seconds", rec->seconds, "Stop after S seconds")->check(CLI::PositiveNumber);
  frames->excludes(secs);
  r->callback([rec] { run_record(*rec); });

  auto rep = std::make_shared<ReplayOptions>();
  auto* p = app.add_subcommand("replay",
                               "Replay a .raw or .neyd capture through the parser and report what it saw");
  p->add_option("file", rep->file, "Capture file (played at max speed, lossless) or a file:// URI")
      ->required();
  p->add_flag("--stats", rep->stats, "Print only the summary: records, pairs, fps, offsets, counters");
  p->add_flag("--json", rep->json, "Print the summary as JSON");
  p->callback([rep] { run_replay(*rep); });
}

}  // namespace naneye::tools
