#include "study.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <opencv2/core/utility.hpp>

namespace naneye::tools::study {

StudyRun run_study(const StudyOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  // One core and a fixed thread count: the same seed gives the same numbers on any machine size.
  cv::setNumThreads(1);
  StudyRun run;
  run.options = o;
  const int views = o.reduced ? o.reduced_views : o.views;
  std::uint64_t seed = o.seed;
  for (const sim::Preset& p : sim::presets()) {
    if (o.reduced && p.name != "paper-d3") continue;
    spdlog::info("study: rendering {} ({} views)", p.name, views);
    Dataset d = render_dataset(p, views, seed++);
    run_methods(d);
    run.sets.push_back(std::move(d));
  }
  for (const Dataset& d : run.sets) {
    if (d.preset.name != "paper-d3") continue;
    run.six = six_point_comparison(d);
    run.noisy.push_back(with_corner_noise(d, kClassicCornerSigmaPx, o.seed + 100));
    run.cross_validation = cross_validation_section(run, d);
  }
  std::filesystem::create_directories(o.out_dir);
  run.figures = write_figures(run.sets, o.out_dir);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_report(run, o.out_dir / "accuracy.md");
  spdlog::info("study: done in {:.1f} s", run.seconds);
  return run;
}

}  // namespace naneye::tools::study
