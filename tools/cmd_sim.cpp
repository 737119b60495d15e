// `naneye sim --preset paper-d3 --pairs N --seed S -o DIR`: a rendered capture with its truth.json.
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "naneye/sim/capture.hpp"

namespace naneye::tools {

void add_sim_commands(CLI::App& app) {
  auto* sim =
      app.add_subcommand("sim", "Render a simulated NanEye Stereo capture with ground truth (truth.json)");
  auto o = std::make_shared<sim::CaptureSettings>();
  auto out = std::make_shared<std::string>();
  auto calib = std::make_shared<std::string>();
  sim->add_option("--preset", o->preset, "paper-d1 | paper-d2 | paper-d3 (the paper's datasets)")
      ->check(CLI::IsMember({"paper-d1", "paper-d2", "paper-d3"}))
      ->capture_default_str();
  sim->add_option("--pairs", o->pairs, "Stereo pairs to render")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sim->add_option("--seed", o->seed, "Seed: the same seed gives the same bytes")->capture_default_str();
  sim->add_option("-o,--out", *out, "Output directory (capture.raw + truth.json)")->required();
  sim->add_option("--format", o->format, "raw | neyd")
      ->transform(CLI::CheckedTransformer(std::map<std::string, sim::CaptureFormat>{
          {"raw", sim::CaptureFormat::raw}, {"neyd", sim::CaptureFormat::neyd}}))
      ->capture_default_str();
  sim->add_flag("--bayer", o->bayer, "GRBG colour sensor (default monochrome)");
  sim->add_flag("--noise-free", o->noise_free,
                "Ideal sensor: no noise, blur, vignetting, defects; uniform light");
  sim->add_option("--calib", *calib, "Calibration YAML instead of the preset's")->check(CLI::ExistingFile);
  sim->add_option("--partial-share", o->partial_share, "Share of pairs with the board partly out of view")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sim->add_option("--absent-share", o->absent_share, "Share of pairs without a board")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  sim->add_option("--start-ticks", o->start_ticks,
                  "First left timestamp (48 MHz ticks; default from the seed)");
  sim->add_option("--bit-flips", o->faults.bit_flip_rate, "Fault: probability per byte of a flipped bit")
      ->check(CLI::Range(0.0, 1.0));
  sim->add_option("--drop-bytes", o->faults.dropped_byte_rate, "Fault: probability per byte of losing it")
      ->check(CLI::Range(0.0, 1.0));
  sim->add_option("--lose-records", o->faults.lost_record_rate, "Fault: probability per record of losing it")
      ->check(CLI::Range(0.0, 1.0));
  sim->add_option("--truncate", o->faults.truncate_tail, "Fault: bytes cut off the end of the stream");
  sim->callback([o, out, calib] {
    o->out_dir = *out;
    o->calibration = *calib;
    const sim::CaptureSummary s = sim::write_capture(*o);
    nlohmann::json j{{"stream", s.stream_file.string()},
                     {"truth", s.truth_file.string()},
                     {"bytes", s.bytes},
                     {"pairs", s.pairs},
                     {"full", s.full},
                     {"partial", s.partial},
                     {"absent", s.absent},
                     {"lost_records", s.lost_records}};
    std::cout << j.dump() << "\n";
  });
}

}  // namespace naneye::tools
