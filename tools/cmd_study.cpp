// `naneye study --preset paper [--reduced] [--out-dir docs] [--seed N]`: the paper's experiments on
// simulated captures with ground truth; writes OUT/accuracy.md and OUT/img/*.png (tools/study/).
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "study/study.hpp"

namespace naneye::tools {

void add_study_commands(CLI::App& app) {
  auto o = std::make_shared<study::StudyOptions>();
  auto preset = std::make_shared<std::string>("paper");
  auto out = std::make_shared<std::string>("docs");
  auto* cmd = app.add_subcommand(
      "study", "Reproduce the paper's accuracy study on simulated captures (writes accuracy.md + plots)");
  cmd->add_option("--preset", *preset, "Which study: paper (Dias et al., ICDSC 2016)")
      ->check(CLI::IsMember({"paper"}))
      ->capture_default_str();
  cmd->add_flag("--reduced", o->reduced, "Dataset 3 only, a few views (for CI)");
  cmd->add_option("--out-dir", *out, "Where accuracy.md and img/*.png go")->capture_default_str();
  cmd->add_option("--seed", o->seed, "Seed: the same seed gives the same numbers")->capture_default_str();
  cmd->add_option("--views", o->views, "Views per dataset (full preset)")
      ->check(CLI::Range(3, 200))
      ->capture_default_str();
  // The callback owns every variable CLI11 writes into (they must outlive parsing).
  cmd->callback([o, out, preset] {
    o->out_dir = *out;
    const study::StudyRun run = study::run_study(*o);
    std::cout << (o->out_dir / "accuracy.md").string() << "\n";
    for (const auto& p : run.figures.png) std::cout << (o->out_dir / p).string() << "\n";
  });
}

}  // namespace naneye::tools
