// The study's plots: corner error against image radius, depth error against distance, and the division
// model's residual against radius (docs/img/*.png).
#include <cmath>

#include "naneye/recon/paper/division_fit.hpp"
#include "plot.hpp"
#include "study.hpp"

namespace naneye::tools::study {
namespace {

const cv::Scalar kBlue(180, 110, 30), kOrange(20, 130, 240), kGreen(60, 160, 60), kRed(50, 50, 210),
    kPurple(160, 80, 140), kGrey(120, 120, 120), kBlack(20, 20, 20);
const cv::Scalar kSetColours[] = {kBlue, kOrange, kGreen};

// Lighter shade of a colour for dense clouds.
cv::Scalar light(const cv::Scalar& c) {
  return (c + cv::Scalar(255, 255, 255) * 1.5) / 2.5;
}

Figure corner_error_figure(const std::vector<Dataset>& sets, double& rms) {
  Figure f{"Detected corner error against image radius (both eyes)",
           "radius from the principal point (px)",
           "corner error |detected - truth| (px)",
           {},
           0.0,
           {},
           0.0,
           {}};
  Series all{"", kBlack, {}, {}, false, 1};
  double sq = 0;
  int n = 0;
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const Dataset& d = sets[s];
    Series cloud{d.preset.name + " corners", light(kSetColours[s % 3]), {}, {}, false, 2};
    for (const View& v : d.views) {
      if (!v.found) continue;
      for (std::size_t i = 0; i < v.detected.size(); ++i) {
        if (!v.detected[i]) continue;
        for (const bool left : {true, false}) {
          const recon::CameraModel& cam = left ? d.rig.left : d.rig.right;
          const Eigen::Vector2d& t = left ? v.truth_left[i] : v.truth_right[i];
          const double e = ((left ? v.left_px[i] : v.right_px[i]) - t).norm();
          cloud.x.push_back((t - Eigen::Vector2d(cam.cx(), cam.cy())).norm());
          cloud.y.push_back(e);
          sq += e * e;
          ++n;
        }
      }
    }
    all.x.insert(all.x.end(), cloud.x.begin(), cloud.x.end());
    all.y.insert(all.y.end(), cloud.y.begin(), cloud.y.end());
    f.series.push_back(std::move(cloud));
  }
  rms = n ? std::sqrt(sq / n) : NAN;
  f.series.push_back(binned_mean(all, 10.0, "naneye's detector: mean over 10 px bins", kBlack));
  // The OpenCV path's corners (findChessboardCorners + cornerSubPix) on the same renders.
  Series ocv{"", kRed, {}, {}, false, 1};
  for (const Dataset& d : sets) {
    for (const View& v : d.views) {
      for (std::size_t i = 0; v.opencv_found && i < v.opencv_left.size(); ++i) {
        for (const bool left : {true, false}) {
          const recon::CameraModel& cam = left ? d.rig.left : d.rig.right;
          const Eigen::Vector2d& t = left ? v.truth_left[i] : v.truth_right[i];
          ocv.x.push_back((t - Eigen::Vector2d(cam.cx(), cam.cy())).norm());
          ocv.y.push_back(((left ? v.opencv_left[i] : v.opencv_right[i]) - t).norm());
        }
      }
    }
  }
  if (!ocv.x.empty())
    f.series.push_back(binned_mean(ocv, 10.0, "OpenCV path corners: mean over 10 px bins", kRed));
  return f;
}

Figure depth_error_figure(const std::vector<Dataset>& sets, double corner_rms) {
  Figure f{"Depth error against distance (every corner of every view)",
           "true depth Z (mm)",
           "|Z - Z_true| (mm)",
           {},
           0.0,
           {},
           0.0,
           {}};
  const Method methods[] = {opencv, div_tri, poly_tri, poly_board};
  const cv::Scalar colours[] = {kOrange, kRed, kBlue, kGreen};
  double zmax = 0;
  for (std::size_t k = 0; k < 4; ++k) {
    Series s{method_name(methods[k]), colours[k], {}, {}, false, 2};
    for (const Dataset& d : sets) {
      for (const View& v : d.views) {
        for (std::size_t i = 0; v.found && i < v.truth_mm.size(); ++i) {
          const Eigen::Vector3d& X = v.points[static_cast<std::size_t>(methods[k])][i];
          if (!X.allFinite()) continue;
          s.x.push_back(v.truth_mm[i].z());
          s.y.push_back(std::abs(X.z() - v.truth_mm[i].z()));
          zmax = std::max(zmax, v.truth_mm[i].z());
        }
      }
    }
    f.series.push_back(std::move(s));
  }
  // Paper Eq. 2: dZ = Z^2 / (f T) dd, with dd the disparity error of two corners of the measured RMS.
  if (!sets.empty() && std::isfinite(corner_rms)) {
    const recon::StereoRig& rig = sets.front().rig;
    const double fT = rig.left.fx() * rig.baseline_mm();
    Series eq{"paper Eq. 2: Z^2 / (f T) * sqrt(2) * corner RMS", kBlack, {}, {}, true, 2};
    for (double z = 0; z <= zmax * 1.05; z += zmax / 100) {
      eq.x.push_back(z);
      eq.y.push_back(z * z / fT * std::sqrt(2.0) * corner_rms);
    }
    f.series.push_back(std::move(eq));
  }
  return f;
}

Figure division_residual_figure(const Dataset& d) {
  Figure f{"One division parameter against the polynomial model (" + d.preset.name + ")",
           "radius from the centre of distortion (px)",
           "|division - polynomial| (raw px)",
           {},
           0.0,
           {},
           0.0,
           {}};
  struct Line {
    bool left;
    recon::DivisionVariant variant;
    bool homography;
    cv::Scalar colour;
  };
  const Line lines[] = {{true, recon::DivisionVariant::image_centre, false, kBlue},
                        {true, recon::DivisionVariant::normalized, false, kGreen},
                        {true, recon::DivisionVariant::image_centre, true, kRed},
                        {false, recon::DivisionVariant::image_centre, false, kOrange},
                        {false, recon::DivisionVariant::normalized, false, kPurple},
                        {false, recon::DivisionVariant::image_centre, true, kGrey}};
  for (const Line& l : lines) {
    const recon::CameraModel& cam = l.left ? d.rig.left : d.rig.right;
    recon::DivisionFit fit;
    std::string label = std::string(l.left ? "left" : "right") + ", " + recon::to_string(l.variant);
    if (l.homography) {
      const double lambda = l.left ? d.lambdas_pixel.lambda_left : d.lambdas_pixel.lambda_right;
      fit = recon::division_residuals(cam, recon::division_frame(cam, l.variant, lambda), 3);
      label += ", lambda from homographies";
    } else {
      fit = recon::fit_division_to_camera(cam, l.variant, 3);
      label += ", best-fit lambda";
    }
    Series cloud{"", l.colour, {}, {}, false, 1};
    for (const auto& s : fit.samples) {
      cloud.x.push_back(s.radius_px);
      cloud.y.push_back(s.residual_px);
    }
    f.series.push_back(binned_mean(cloud, 4.0, label + " (mean per 4 px)", l.colour));
  }
  return f;
}

}  // namespace

FigureFiles write_figures(const std::vector<Dataset>& sets, const std::filesystem::path& out_dir) {
  std::filesystem::create_directories(out_dir / "img");
  FigureFiles files;
  double corner_rms = NAN;
  const Figure corners = corner_error_figure(sets, corner_rms);
  const auto put = [&](const Figure& f, const std::string& name) {
    save_figure(f, out_dir / "img" / name);
    files.png.push_back("img/" + name);
  };
  put(corners, "corner-error-vs-radius.png");
  put(depth_error_figure(sets, corner_rms), "depth-error-vs-distance.png");
  for (const Dataset& d : sets) {
    if (d.preset.name == "paper-d3") put(division_residual_figure(d), "division-residual-vs-radius.png");
  }
  return files;
}

}  // namespace naneye::tools::study
