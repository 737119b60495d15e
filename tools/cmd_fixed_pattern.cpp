// `naneye fixed-pattern --dark URI [--flat URI] [--frames N] -o FILE`: measure the sensor's fixed
// pattern (per-pixel dark offsets from frames with the lens capped; per-pixel gains from frames of a
// uniform white target), print what it holds and write the file naneyed's [sensor] fixed_pattern and
// `naneye recon --fixed-pattern` read (docs/sensor-calibration.md). Nothing is written when anything
// fails.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "cli_inputs.hpp"
#include "commands.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/app/sources.hpp"
#include "naneye/recon/camera/fixed_pattern_io.hpp"
#include "replace_file.hpp"
#include "source_pairs.hpp"

namespace naneye::tools {
namespace {

struct FixedPatternOptions {
  std::string dark, flat, output;
  int frames = 64;  // 1.3 s of a 50 fps camera; the maps' error: docs/sensor-calibration.md
};

// Feeds `frames` pairs of the source to both eyes' builders; std::runtime_error when the source ends
// or fails before.
void collect(const std::string& uri, int frames, bool dark, recon::FixedPatternBuilder& left,
             recon::FixedPatternBuilder& right) {
  auto source = app::make_source_registry().open(lossless_input_uri(uri));
  source->start();
  const long long n = for_each_pair(*source, frames, [&](driver::StereoPair& pair) {
    const recon::RawImageView l = app::image_view(pair.left), r = app::image_view(pair.right);
    if (dark) {
      left.add_dark(l);
      right.add_dark(r);
    } else {
      left.add_flat(l);
      right.add_flat(r);
    }
  });
  source->stop();
  if (auto err = source->error()) throw std::runtime_error(uri + ": " + *err);
  if (n < frames)
    throw std::runtime_error(uri + ": ended after " + std::to_string(n) + " pairs, --frames asks for " +
                             std::to_string(frames));
}

void print_eye(const char* name, const recon::FixedPattern& p) {
  std::printf("%-5s  black %.1f DN  DSNU + column FPN %.2f DN (map se %.2f DN, %d dark frames)", name,
              p.black_dn, p.dsnu_dn, p.dark_se_dn, p.dark_frames);
  if (p.gain.empty())
    std::printf("  no gains (no flat frames)\n");
  else
    std::printf("  PRNU %.2f %% (map se %.2f %%, %d flat frames)\n", 100 * p.prnu, 100 * p.gain_se,
                p.flat_frames);
}

void run(const FixedPatternOptions& o) {
  recon::FixedPatternBuilder left, right;
  collect(o.dark, o.frames, true, left, right);
  if (!o.flat.empty()) collect(o.flat, o.frames, false, left, right);
  const recon::StereoFixedPattern pattern{left.build(), right.build()};
  print_eye("left", pattern.left);
  print_eye("right", pattern.right);
  const std::filesystem::path out(o.output);
  replace_file(out, [&](const std::filesystem::path& tmp) { recon::save_fixed_pattern(tmp, pattern); });
  spdlog::info("wrote {}: set [sensor] fixed_pattern = \"{}\" in naneyed.toml", out.string(),
               std::filesystem::absolute(out).string());
}

}  // namespace

void add_fixed_pattern_commands(CLI::App& app) {
  auto o = std::make_shared<FixedPatternOptions>();
  auto* cmd = app.add_subcommand(
      "fixed-pattern",
      "Measure the sensor's fixed pattern (dark offsets, pixel gains) from capped and flat-field frames");
  cmd->add_option("--dark", o->dark, "Source URI or capture of the camera with the lens capped (no light)")
      ->required();
  cmd->add_option("--flat", o->flat,
                  "Source URI or capture of a uniform white target filling the view (not saturated); "
                  "without it, offsets only");
  const int min_frames = recon::FixedPatternSettings{}.min_dark_frames;
  cmd->add_option("--frames", o->frames,
                  "Pairs averaged from each source (at least " + std::to_string(min_frames) +
                      ": fewer add more noise than they remove)")
      ->capture_default_str()
      ->check(CLI::Range(min_frames, 100000));
  cmd->add_option("-o,--output", o->output, "The fixed-pattern file to write (.yml.gz or .yml)")->required();
  cmd->callback([o] { run(*o); });
}

}  // namespace naneye::tools
