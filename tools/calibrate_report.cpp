// The report of `naneye calibrate`, laid out like Bouguet's toolbox and mrcal print theirs: every
// parameter with its one-sigma uncertainty, the residuals overall and per view, and the
// cross-validation tables when asked.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "calibrate_views.hpp"

namespace naneye::tools {
namespace {

nlohmann::json parameter_json(const recon::ParameterEstimate& p) {
  return {{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}, {"fixed", p.fixed}};
}

void print_camera(const recon::CalibrationResult& res, const char* eye) {
  std::printf("%s camera\n", eye);
  for (const char* name : {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"}) {
    const recon::ParameterEstimate* p = res.find(std::string(eye) + "." + name);
    if (p->fixed)
      std::printf("  %-3s %12.6f   (fixed)\n", name, p->value);
    else
      std::printf("  %-3s %12.6f +- %-10.6f\n", name, p->value, p->sigma);
  }
}

void print_splits(const recon::SplitValidation& v) {
  std::printf("\ncross-validation: calibrate on %zu views, reconstruct the others (the paper's scheme)\n",
              v.splits.empty() ? std::size_t{0} : v.splits[0].train.size());
  std::printf("  split  train  test  calib RMS px   P mm      D mm      R px\n");
  for (std::size_t s = 0; s < v.splits.size(); ++s) {
    const auto& sp = v.splits[s];
    if (!sp.ok) {
      std::printf("  %5zu  %5zu  %4zu  failed: %s\n", s + 1, sp.train.size(), sp.test.size(),
                  sp.message.c_str());
      continue;
    }
    std::printf("  %5zu  %5zu  %4zu  %12.4f  %8.4f  %8.4f  %8.4f\n", s + 1, sp.train.size(), sp.test.size(),
                sp.calibration_rms_px, sp.planarity_mm, sp.distance_mm, sp.reprojection_px);
  }
  std::printf("  mean                                %8.4f  %8.4f  %8.4f\n", v.planarity_mm, v.distance_mm,
              v.reprojection_px);
}

void print_odd_even(const recon::OddEvenValidation& v) {
  std::printf(
      "\ncross-validation: odd views against even views (|odd - even| should be about the combined sigma)\n");
  if (!v.ok) {
    std::printf("  failed: %s\n", v.message.c_str());
    return;
  }
  std::printf("  %-9s %12s %12s %11s %11s %6s\n", "parameter", "odd", "even", "difference", "comb. sigma",
              "ratio");
  for (const auto& c : v.parameters) {
    if (c.fixed) continue;
    std::printf("  %-9s %12.6f %12.6f %11.6f %11.6f %6.2f\n", c.name.c_str(), c.odd, c.even, c.difference,
                c.combined_sigma, c.ratio);
  }
  std::printf("  RMS of the ratios: %.2f (about 1 when the sigmas are honest)\n", v.ratio_rms);
  if (v.depth_corners == 0) return;
  std::printf(
      "  depth of the %d corners both eyes saw, triangulated with each half: median |odd - even| %.3f %% of "
      "Z,\n"
      "  median combined calibration sigma %.3f %% of Z, RMS of the ratios %.2f (about 1 when the depth "
      "sigma is honest;\n  %.2f with the marginal sigmas taken as independent)\n",
      v.depth_corners, 100.0 * v.depth_median_relative, 100.0 * v.depth_sigma_median_relative,
      v.depth_ratio_rms, v.depth_ratio_rms_independent);
  std::printf(
      "  the same test over %zu ways to halve the views (odd/even, index mod 4 {0,1}/{2,3}, {0,3}/{1,2}):",
      v.split_depth_ratio_rms.size());
  for (double r : v.split_depth_ratio_rms) std::printf(" %.2f", r);
  std::printf(", pooled over %d corners %.2f\n", v.pooled_depth_corners, v.pooled_depth_ratio_rms);
  if (v.sigma_scale > 1.0)
    std::printf(
        "  beyond the %.1f that honest sigmas reach by chance: the calibration's sigmas understate, and the "
        "file's\n"
        "  calibration_sigma_scale %.2f widens every calibration sigma by it (a lower bound: errors both "
        "halves\n"
        "  share do not show here)\n",
        recon::kHonestDepthRatioRmsMax, v.sigma_scale);
  else
    std::printf("  within the %.1f that honest sigmas reach by chance: the covariance is kept as it is\n",
                recon::kHonestDepthRatioRmsMax);
}

}  // namespace

nlohmann::json report_json(const recon::CalibrationResult& res, const CollectedViews& views,
                           const recon::SplitValidation* splits, const recon::OddEvenValidation* odd_even) {
  nlohmann::json j;
  j["ok"] = res.ok;
  j["message"] = res.message;
  j["pairs"] = views.pairs;
  j["views_detected"] = views.views.size();
  j["views_used"] = res.used_views.size();
  j["pairs_without_board"] = views.no_board;
  j["rms_px"] = res.rms_px;
  j["worst_px"] = res.worst_px;
  j["sigma_px"] = res.sigma_px;
  j["initial_rms_px"] = res.initial_rms_px;
  j["residuals"] = res.residuals;
  j["free_parameters"] = res.free_parameters;
  j["iterations"] = res.iterations;
  for (const auto& p : res.parameters) j["parameters"].push_back(parameter_json(p));
  for (const auto& v : res.views) {
    const auto& src = views.sources[static_cast<std::size_t>(v.view)];
    j["views"].push_back({{"view", v.view},
                          {"input", src.input},
                          {"pair", src.pair},
                          {"left_corners", v.left_corners},
                          {"right_corners", v.right_corners},
                          {"rms_left_px", v.rms_left_px},
                          {"rms_right_px", v.rms_right_px},
                          {"rms_px", v.rms_px},
                          {"worst_px", v.worst_px}});
  }
  if (splits) {
    for (const auto& s : splits->splits)
      j["cross_validation"]["splits"].push_back({{"train", s.train},
                                                 {"test", s.test},
                                                 {"ok", s.ok},
                                                 {"message", s.message},
                                                 {"calibration_rms_px", s.calibration_rms_px},
                                                 {"planarity_mm", s.planarity_mm},
                                                 {"distance_mm", s.distance_mm},
                                                 {"reprojection_px", s.reprojection_px}});
    j["cross_validation"]["mean"] = {{"planarity_mm", splits->planarity_mm},
                                     {"distance_mm", splits->distance_mm},
                                     {"reprojection_px", splits->reprojection_px}};
  }
  if (odd_even) {
    auto& o = j["cross_validation"]["odd_even"];
    o["ok"] = odd_even->ok;
    o["message"] = odd_even->message;
    o["ratio_rms"] = odd_even->ratio_rms;
    o["depth"] = {{"corners", odd_even->depth_corners},
                  {"ratio_rms", odd_even->depth_ratio_rms},
                  {"ratio_rms_marginals_independent", odd_even->depth_ratio_rms_independent},
                  {"median_relative_difference", odd_even->depth_median_relative},
                  {"median_relative_combined_sigma", odd_even->depth_sigma_median_relative},
                  {"split_ratio_rms", odd_even->split_depth_ratio_rms},
                  {"pooled_corners", odd_even->pooled_depth_corners},
                  {"pooled_ratio_rms", odd_even->pooled_depth_ratio_rms},
                  {"sigma_scale", odd_even->sigma_scale}};
    for (const auto& c : odd_even->parameters)
      o["parameters"].push_back({{"name", c.name},
                                 {"odd", c.odd},
                                 {"even", c.even},
                                 {"odd_sigma", c.odd_sigma},
                                 {"even_sigma", c.even_sigma},
                                 {"difference", c.difference},
                                 {"combined_sigma", c.combined_sigma},
                                 {"ratio", c.ratio},
                                 {"fixed", c.fixed}});
  }
  return j;
}

void print_report(const recon::CalibrationResult& res, const CollectedViews& views,
                  const recon::SplitValidation* splits, const recon::OddEvenValidation* odd_even,
                  const recon::CalibrationSettings& settings, const ReportOptions& o) {
  if (o.json) {
    std::cout << report_json(res, views, splits, odd_even).dump() << "\n";
    return;
  }
  std::printf(
      "naneye calibrate: %zu views used of %lld pairs (%lld without a full board in either eye, %lld "
      "with one eye only)\n",
      res.used_views.size(), views.pairs, views.no_board, views.one_eye);
  std::printf("model: pinhole (skew 0) + polynomial radial k1 k2 %s%s; uncertainties are one sigma\n\n",
              settings.fix_k3 ? "(k3 fixed at 0)" : "k3", settings.tangential ? " + tangential p1 p2" : "");
  print_camera(res, "left");
  print_camera(res, "right");
  std::printf("stereo pose (X_right = R X_left + T)\n");
  for (const char* name : {"om.x", "om.y", "om.z"}) {
    const auto* p = res.find(name);
    std::printf("  %-4s %12.6f +- %-10.6f rad\n", name, p->value, p->sigma);
  }
  for (const char* name : {"T.x", "T.y", "T.z"}) {
    const auto* p = res.find(name);
    std::printf("  %-4s %12.6f +- %-10.6f mm\n", name, p->value, p->sigma);
  }
  std::printf("  baseline %.4f mm, rotation %.4f deg\n\n", res.rig.baseline_mm(),
              res.rig.rotation_angle_rad() * 180.0 / M_PI);
  std::printf("residuals: RMS %.4f px per corner, worst %.4f px, noise estimate %.4f px per coordinate\n",
              res.rms_px, res.worst_px, res.sigma_px);
  std::printf(
      "           n = %d residuals, k = %d free parameters, %d iterations (initial guess RMS %.4f px)\n\n",
      res.residuals, res.free_parameters, res.iterations, res.initial_rms_px);
  std::printf("  view  pair  input                          left  right  RMS L px  RMS R px   worst px\n");
  for (const auto& v : res.views) {
    const auto& src = views.sources[static_cast<std::size_t>(v.view)];
    std::string input = src.input;
    if (input.size() > 30) input = "..." + input.substr(input.size() - 27);
    std::printf("  %4d  %4llu  %-30s  %4d  %5d  %8.4f  %8.4f  %9.4f\n", v.view, src.pair, input.c_str(),
                v.left_corners, v.right_corners, v.rms_left_px, v.rms_right_px, v.worst_px);
  }
  if (splits) print_splits(*splits);
  if (odd_even) print_odd_even(*odd_even);
  if (!o.output.empty()) std::printf("\nwrote %s\n", o.output.c_str());
}

}  // namespace naneye::tools
