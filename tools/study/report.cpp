// docs/accuracy.md: tables shaped like the paper's, our figures beside the paper's own.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "format.hpp"
#include "naneye/recon/paper/division_fit.hpp"
#include "paper_tables.hpp"
#include "study.hpp"

namespace naneye::tools::study {
namespace {

const Dataset* find_set(const StudyRun& run, const std::string& name) {
  for (const Dataset& d : run.sets) {
    if (d.preset.name == name) return &d;
  }
  return nullptr;
}

// The first five found views stand for the paper's five planes (its were five of its 19 images too;
// they are not the same boards, so compare the ranges, not the rows).
std::vector<const View*> five_views(const Dataset& d) {
  std::vector<const View*> v;
  for (const View& x : d.views) {
    if (x.found && v.size() < 5) v.push_back(&x);
  }
  return v;
}

paper::PDR paper_mean(const paper::FivePlanes& t) {
  paper::PDR m{0, 0, 0};
  for (const auto& p : t) {
    m.P += p.P / 5;
    m.D += p.D / 5;
    m.R += p.R / 5;
  }
  return m;
}

// One of the paper's per-plane tables: the paper, then `method`, then our polynomial pipeline beside it.
void plane_table(std::ostream& o, const Dataset& d, const std::string& title, const paper::FivePlanes& paper,
                 Method method) {
  o << "### " << title << "\n\n";
  o << "P, D in mm, R in px, as \"P / D / R\"; E = 3D RMS error against the truth (mm), which the paper "
       "could not measure.\n\n";
  o << "| plane | paper | ours: " << method_name(method) << " | E |";
  if (method != poly_tri) o << " ours: " << method_name(poly_tri) << " | E |";
  o << " ours: board pose, R | E | OpenCV path | E |\n|---|---|---|---|"
    << (method != poly_tri ? "---|---|" : "") << "---|---|---|---|\n";
  const auto views = five_views(d);
  const auto row = [&](const std::string& name, const std::string& p,
                       const std::array<Scores, kMethodCount>& s) {
    o << "| " << name << " | " << p << " | " << pdr(s[method]) << " | " << num(s[method].E) << " |";
    if (method != poly_tri) o << " " << pdr(s[poly_tri]) << " | " << num(s[poly_tri].E) << " |";
    o << " " << num(s[poly_board].R) << " | " << num(s[poly_board].E, 4) << " | " << pdr(s[opencv]) << " | "
      << num(s[opencv].E) << " |\n";
  };
  for (std::size_t k = 0; k < views.size(); ++k)
    row("Plane " + std::to_string(k + 1), pdr(paper[k]), views[k]->scores);
  row("mean (paper: its 5; ours: " + std::to_string(d.found) + " views)", pdr(paper_mean(paper)), d.mean);
  o << "\n";
}

void datasets_table(std::ostream& o, const StudyRun& run) {
  o << "| dataset | truth rig | board | distance | views found | lambda, lambda' image centre (px^-2) | "
       "transfer RMS (px) | lambda, lambda' normalized | best-fit lambda image centre, left / right |\n"
       "|---|---|---|---|---|---|---|---|---|\n";
  for (const Dataset& d : run.sets) {
    const auto fl = recon::fit_division_to_camera(d.rig.left, recon::DivisionVariant::image_centre, 4);
    const auto fr = recon::fit_division_to_camera(d.rig.right, recon::DivisionVariant::image_centre, 4);
    o << "| " << d.preset.name << " | config/calib/" << d.preset.calib_file << " | 9 x 7 squares of "
      << num(d.board.square_mm, 2) << " mm | ~" << num(d.preset.distance_mm, 0) << " mm | " << d.found
      << " (OpenCV path: " << d.opencv_found << ") / " << d.views.size() << " | "
      << num(d.lambdas_pixel.lambda_left) << ", " << num(d.lambdas_pixel.lambda_right) << " | "
      << num(d.lambdas_pixel.rms) << " | " << num(d.lambdas_normalized.lambda_left) << ", "
      << num(d.lambdas_normalized.lambda_right) << " | " << num(fl.lambda) << " / " << num(fr.lambda)
      << " |\n";
  }
  o << "\n";
}

std::string noisy_name(const Dataset& d) {
  return d.preset.name + " + " + num(kClassicCornerSigmaPx, 1) + " px corner noise";
}

void summary_table(std::ostream& o, const StudyRun& run) {
  o << "| dataset | method | P (mm) | D (mm) | R (px) | E (mm) | points |\n|---|---|---|---|---|---|---|\n";
  std::vector<std::pair<const Dataset*, std::string>> all;
  for (const Dataset& d : run.sets) all.emplace_back(&d, d.preset.name);
  for (const Dataset& d : run.noisy) all.emplace_back(&d, noisy_name(d));
  for (const auto& [d, name] : all) {
    for (int m = 0; m < kMethodCount; ++m) {
      const Scores& s = d->mean[static_cast<std::size_t>(m)];
      o << "| " << name << " | " << method_name(static_cast<Method>(m)) << " | " << num(s.P) << " | "
        << num(s.D) << " | " << num(s.R) << " | " << num(s.E, 4) << " | " << s.valid << " |\n";
    }
  }
  o << "\n";
}

// The paper's means beside ours, with naneye's corners and with a classic detector's corner noise.
void noise_table(std::ostream& o, const Dataset& clean, const Dataset& noisy) {
  o << "| method | paper, mean of its 5 planes | ours, naneye's corners | E | ours, + "
    << num(kClassicCornerSigmaPx, 1) << " px corner noise | E |\n|---|---|---|---|---|---|\n";
  const std::pair<Method, const paper::FivePlanes*> rows[] = {{poly_dlt, &paper::kBaseline},
                                                              {poly_tri, nullptr},
                                                              {poly_board, nullptr},
                                                              {div_tri, &paper::kDivisionTriangulation},
                                                              {div_sweep, &paper::kDivisionSweep},
                                                              {norm_tri, &paper::kNormalizedTriangulation},
                                                              {norm_direct, &paper::kNormalizedDirect},
                                                              {opencv, &paper::kBaseline}};
  for (const auto& [m, p] : rows) {
    o << "| " << method_name(m) << " | " << (p ? pdr(paper_mean(*p)) : "-") << " | " << pdr(clean.mean[m])
      << " | " << num(clean.mean[m].E, 4) << " | " << pdr(noisy.mean[m]) << " | " << num(noisy.mean[m].E, 4)
      << " |\n";
  }
  o << "\n";
}

void six_point_tables(std::ostream& o, const StudyRun& run) {
  o << "P, D in mm; R(own) reprojects with the method's own model, R(true) with the true polynomial camera "
       "(px). Paper: \"P / D / R\".\n\n";
  for (const SixPointResult& s : run.six) {
    o << "**" << s.placement << "** (centre " << num(s.offset_px, 0)
      << " px from the left principal point, 70 mm)\n\n"
         "| method | paper | P | D | R(own) | R(true) |\n|---|---|---|---|---|---|\n";
    const std::pair<Method, std::string> rows[] = {{poly_dlt, pdr(paper::kSixBaseline)},
                                                   {div_tri, pdr(paper::kSixDivisionTriangulation)},
                                                   {div_sweep, pdr(paper::kSixDivisionSweep)},
                                                   {norm_tri, "-"},
                                                   {norm_direct, "-"}};
    for (const auto& [m, p] : rows) {
      const SixPointRow& r = s.rows[m];
      o << "| " << method_name(m) << " | " << p << " | " << num(r.P) << " | " << num(r.D) << " | "
        << num(r.R_own) << " | " << num(r.R_true) << " |\n";
    }
    o << "\n";
  }
}

}  // namespace

void write_report(const StudyRun& run, const std::filesystem::path& file) {
  std::ostringstream o;
  const StudyOptions& opt = run.options;
  o << "# Accuracy: the paper's study, reproduced on simulated captures\n\n"
       "Regenerate this file and its plots (docs/img/) with one command, from a build of the repository:\n\n"
       "    build/tools/naneye study --preset paper --out-dir docs\n\n"
       "(deterministic: the same build and `--seed` give the same numbers; this run: seed "
    << opt.seed << ", " << (opt.reduced ? "reduced" : "full")
    << " preset; the full preset takes about ten seconds on one core). The paper is Dias, Araujo, Miraldo, "
       "*3D Reconstruction with Low Resolution, Small Baseline and "
       "High Radial Distortion Stereo Images*, ICDSC 2016 (`shared/paper/`).\n\n";

  o << "## Setup\n\n"
       "Each dataset is rendered by the simulator (docs/simulator.md) with the paper's calibration of that "
       "dataset as the *true* rig, the paper's 9 x 7 squares board with that dataset's square size, at its "
       "distance, with the default sensor (shot and read noise, blur, vignetting, defect pixels: the noise "
       "of "
       "the bundled captures). Corners are found by naneye's own detector (docs/corners.md), full search on "
       "every view. The division lambdas are estimated as the paper did, from the plane homographies between "
       "the two views of every board (Eq. 8-9, docs/division-model.md); K, R, T are the calibration's. "
       "Because the truth is known, every table also gives **E**, the 3D RMS error of the reconstructed "
       "corners against the true ones.\n\n";
  datasets_table(o, run);

  o << "## Summary: every method on every dataset (means over the found views)\n\n";
  summary_table(o, run);
  o << "The board-pose rows place the known board geometry at the pose fitted to both eyes, so their P and D "
       "are zero by construction; their E is what matters.\n\n";

  if (const Dataset* d3 = find_set(run, "paper-d3")) {
    if (!run.noisy.empty()) {
      o << "## Where we stand: the paper's means beside ours (Dataset 3)\n\n"
           "P / D / R as in the paper. naneye's detector places the rendered corners far better than the "
           "paper's toolchain placed real ones (see below), so the same views are also given with "
        << num(kClassicCornerSigmaPx, 1)
        << " px of Gaussian noise added to every corner coordinate: the level the paper's millimetres point "
           "to, and what findChessboardCorners + cornerSubPix(3x3) measured on renders of this camera in "
           "shared/notes/measurements.md (0.15-0.22 px; the OpenCV path below, a 7 x 7 window on the float "
           "luminance, does better on these renders). The OpenCV path keeps its own corners, so it has no "
           "figure in the noisy column.\n\n";
      noise_table(o, *d3, run.noisy.front());
    }
    o << "## The paper's tables (Dataset 3: 5.99 mm squares at ~70 mm)\n\n";
    plane_table(o, *d3,
                "Baseline: polynomial model, undistort, triangulate (paper Table \"baseline approach\")",
                paper::kBaseline, poly_dlt);
    plane_table(o, *d3,
                "Division model with triangulation (paper Table \"division model with triangulation\")",
                paper::kDivisionTriangulation, div_tri);
    plane_table(o, *d3, "Division model with plane sweep (paper Table \"division model with plane-sweep\")",
                paper::kDivisionSweep, div_sweep);
    plane_table(o, *d3,
                "Normalized division: undistort, then triangulate (paper Table \"normalized coordinates, "
                "un-distortion and then triangulation\")",
                paper::kNormalizedTriangulation, norm_tri);
    plane_table(o, *d3,
                "Normalized division: triangulate the distorted points directly, Eq. 10 (paper Table "
                "\"triangulating with distorted coordinates\")",
                paper::kNormalizedDirect, norm_direct);
    o << "## The six-point comparison (paper Table \"Comparison of distortion models\")\n\n"
         "Six points 2.189 mm apart (a 2 x 3 grid) projected noise-free with the Dataset 3 polynomial rig, "
         "reconstructed with the lambdas the homographies gave on the rendered Dataset 3 views above. The "
         "paper does not say where its points were; the division model's error depends steeply on it, so "
         "three placements are given.\n\n";
    six_point_tables(o, run);
  }
  o << run.cross_validation;

  o << "## Plots\n\n";
  for (const auto& png : run.figures.png) o << "![" << png << "](" << png << ")\n\n";
  o << differences_section(run);

  std::ofstream f(file);
  if (!f) throw std::runtime_error("cannot write " + file.string());
  f << o.str();
}

}  // namespace naneye::tools::study
