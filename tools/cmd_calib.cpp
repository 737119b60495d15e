// `naneye calib info FILE... [--json]`: what a calibration says, and how far it can be trusted.
// `naneye calib export FILE... --format ros|opencv|mrcal --out DIR`: the same calibration for the
// tools users already have (calib_export.hpp).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "calib_export.hpp"
#include "commands.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "naneye/recon/camera/domain_report.hpp"
#include "naneye/recon/camera/rig_validate.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"

namespace naneye::tools {
namespace {

nlohmann::json camera_json(const recon::CameraModel& cam) {
  const recon::DomainReport d = recon::analyze_domain(cam);
  const auto& K = cam.K();
  const auto& D = cam.distortion();
  nlohmann::json j;
  j["K"] = {{K(0, 0), K(0, 1), K(0, 2)}, {K(1, 0), K(1, 1), K(1, 2)}, {K(2, 0), K(2, 1), K(2, 2)}};
  j["D"] = {D.k1, D.k2, D.p1, D.p2, D.k3};
  j["fold_radius_px"] = d.fold_radius_px ? nlohmann::json(*d.fold_radius_px) : nlohmann::json(nullptr);
  j["valid_pixel_share"] = d.valid_share();
  j["max_roundtrip_error_px"] = d.max_roundtrip_error_px;
  j["max_undistort_iterations"] = d.max_iterations;
  return j;
}

void print_calibration_text(const nlohmann::json& j) {
  for (const char* side : {"left", "right"}) {
    const auto& c = j[side];
    std::cout << side << " camera\n";
    std::cout << "  fx fy cx cy        " << c["K"][0][0] << " " << c["K"][1][1] << " " << c["K"][0][2] << " "
              << c["K"][1][2] << "\n";
    std::cout << "  k1 k2 p1 p2 k3     " << c["D"][0] << " " << c["D"][1] << " " << c["D"][2] << " "
              << c["D"][3] << " " << c["D"][4] << "\n";
    if (c["fold_radius_px"].is_null())
      std::cout << "  fold radius        none (the model is monotonic: every pixel is valid)\n";
    else
      std::cout << "  fold radius        " << c["fold_radius_px"].get<double>() << " px\n";
    std::cout << "  valid pixels       " << 100.0 * c["valid_pixel_share"].get<double>() << " %\n";
    std::cout << "  undistort max round-trip error " << c["max_roundtrip_error_px"].get<double>() << " px\n";
  }
  std::cout << "rig\n  baseline           " << j["rig"]["baseline_mm"].get<double>() << " mm\n"
            << "  rotation           " << j["rig"]["rotation_deg"].get<double>() << " deg\n";
  const auto print_axis = [](const nlohmann::json& on_axis) {
    for (const auto& p : on_axis)
      std::cout << "  Z " << p["z_mm"].get<double>() << " mm    " << p["sigma_mm"].get<double>() << " mm ("
                << 100.0 * p["sigma_mm"].get<double>() / p["z_mm"].get<double>() << " %)\n";
  };
  if (!j["calibration_depth_sigma"].is_null()) {
    std::cout << "depth sigma the calibration allows (its covariance; on the left optical axis, 10 to 70 "
                 "baselines)\n";
    if (const double k = j["calibration_depth_sigma"]["scale"].get<double>(); k != 1.0)
      std::cout << "  widened " << k
                << "x: the understatement its cross-validation measured when it was made "
                   "(calibration_sigma_scale)\n";
    print_axis(j["calibration_depth_sigma"]["on_axis"]);
    return;
  }
  std::cout << "depth sigma the calibration allows: unknown (no calibration_covariance in the file; "
               "`naneye calibrate` writes one)\n";
  if (j["calibration_depth_sigma_if_independent"].is_null()) return;
  std::cout << "  what-if, its *_sigma entries taken as independent (their correlations are not known, "
               "so this is no bound either way):\n";
  print_axis(j["calibration_depth_sigma_if_independent"]["on_axis"]);
}

// What the calibration's own uncertainty allows a depth (geometry/calibration_uncertainty.hpp), on
// the left optical axis at 10, 20, 40 and 70 baselines (the NanEye's 11-76 mm, the scene paths'
// range), where the right eye sees that point.
nlohmann::json on_axis_json(const recon::StereoRig& rig,
                            const std::optional<recon::CalibrationUncertainty>& u) {
  if (!u) return nullptr;
  nlohmann::json points = nlohmann::json::array();
  const double scale =
      u->basis() == recon::CalibrationUncertainty::Basis::full_covariance ? rig.sigmas.covariance_scale : 1.0;
  for (double baselines : {10.0, 20.0, 40.0, 70.0}) {
    const Eigen::Vector3d X(0.0, 0.0, baselines * rig.baseline_mm());
    const Eigen::Vector2d pr = rig.right.project(Eigen::Vector3d(rig.R * X + rig.T));
    if (!(pr.x() >= 0 && pr.y() >= 0 && pr.x() <= rig.right.width() - 1 &&
          pr.y() <= rig.right.height() - 1) ||
        !rig.right.in_domain(pr))
      continue;
    points.push_back({{"z_mm", X.z()}, {"sigma_mm", u->depth_sigma_mm(X)}});
  }
  return {{"on_axis", points}, {"scale", scale}};
}

}  // namespace

void add_calib_commands(CLI::App& app) {
  auto* calib = app.add_subcommand("calib", "Calibration files");
  calib->require_subcommand(1);
  auto* info =
      calib->add_subcommand("info", "Describe a calibration: models, valid domain, undistort accuracy");
  auto files = std::make_shared<std::vector<std::string>>();
  auto json = std::make_shared<bool>(false);
  info->add_option("files", *files, "Calibration YAML (one file, or intrinsics and extrinsics)")
      ->required()
      ->check(CLI::ExistingFile);
  info->add_flag("--json", *json, "Print JSON");
  info->callback([files, json] {
    std::vector<std::filesystem::path> paths(files->begin(), files->end());
    const recon::StereoRig rig = recon::load_rig(paths);
    // What naneyed refuses at start and on SIGHUP is refused here too: describing it would print
    // figures (a fold radius, a valid share) of a model that cannot exist.
    if (auto problem = recon::rig_problem(rig))
      throw recon::CalibrationError(files->front() + ": not a usable calibration: " + *problem);
    nlohmann::json j;
    j["files"] = *files;
    j["image_size"] = {rig.left.width(), rig.left.height()};
    j["left"] = camera_json(rig.left);
    j["right"] = camera_json(rig.right);
    const auto C = rig.right_center();
    j["rig"] = {{"R",
                 {{rig.R(0, 0), rig.R(0, 1), rig.R(0, 2)},
                  {rig.R(1, 0), rig.R(1, 1), rig.R(1, 2)},
                  {rig.R(2, 0), rig.R(2, 1), rig.R(2, 2)}}},
                {"T_mm", {rig.T.x(), rig.T.y(), rig.T.z()}},
                {"right_center_mm", {C.x(), C.y(), C.z()}},
                {"baseline_mm", rig.baseline_mm()},
                {"rotation_deg", rig.rotation_angle_rad() * 180.0 / M_PI}};
    j["calibration_depth_sigma"] = on_axis_json(rig, recon::CalibrationUncertainty::of(rig));
    j["calibration_depth_sigma_if_independent"] =
        on_axis_json(rig, recon::CalibrationUncertainty::assuming_independent_sigmas(rig));
    if (*json)
      std::cout << j.dump(2) << "\n";
    else
      print_calibration_text(j);
  });

  auto* exp = calib->add_subcommand(
      "export", "Write a calibration as ROS camera_info, OpenCV stereo YAML or mrcal models");
  auto ex_files = std::make_shared<std::vector<std::string>>();
  auto format = std::make_shared<std::string>();
  auto out_dir = std::make_shared<std::string>();
  exp->add_option("files", *ex_files, "Calibration YAML (one file, or intrinsics and extrinsics)")
      ->required()
      ->check(CLI::ExistingFile);
  exp->add_option("--format", *format,
                  "ros (left.yaml, right.yaml), opencv (stereo.yml) or mrcal (*.cameramodel)")
      ->required()
      ->check(CLI::IsMember({"ros", "opencv", "mrcal"}));
  exp->add_option("--out", *out_dir, "Folder to write into (created if missing)")->required();
  exp->callback([ex_files, format, out_dir] {
    const recon::StereoRig rig =
        recon::load_rig(std::vector<std::filesystem::path>(ex_files->begin(), ex_files->end()));
    if (auto problem = recon::rig_problem(rig))
      throw recon::CalibrationError(ex_files->front() + ": not a usable calibration: " + *problem);
    std::filesystem::create_directories(*out_dir);
    const auto written = *format == "ros"      ? export_ros(rig, *out_dir)
                         : *format == "opencv" ? export_opencv(rig, *out_dir)
                                               : export_mrcal(rig, *out_dir);
    for (const auto& p : written) std::cout << p.string() << "\n";
  });
}

}  // namespace naneye::tools
