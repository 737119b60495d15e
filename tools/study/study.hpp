#pragma once
// `naneye study --preset paper`: the paper's experiments (Dias et al., ICDSC 2016, Sec. 4) on simulated
// captures of its three datasets, with the ground truth the paper did not have. One file per step:
// dataset.cpp renders and detects, methods.cpp reconstructs with every method and scores it,
// six_points.cpp is the paper's synthetic comparison, figures.cpp the plots, report.cpp docs/accuracy.md.
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "naneye/recon/camera/rig.hpp"
#include "naneye/recon/geometry/board_pose.hpp"
#include "naneye/recon/paper/division_homography.hpp"
#include "naneye/sim/presets.hpp"

namespace naneye::tools::study {

struct StudyOptions {
  bool reduced = false;  // CI: Dataset 3 only, a few views
  std::filesystem::path out_dir = "docs";
  std::uint64_t seed = 2016;
  int views = 19;  // per dataset, as the paper had (reduced: reduced_views)
  int reduced_views = 6;
};

// The reconstruction methods compared, in table order.
enum Method : int {
  poly_tri,     // polynomial model, exact undistortion, niter2 + raw-pixel refinement (our pipeline)
  poly_dlt,     // polynomial model, exact undistortion, linear triangulation (the paper's baseline recipe)
  poly_board,   // polynomial model, board pose from both eyes (board_pose.hpp)
  div_tri,      // division model about the image centre, undistort, DLT (paper Table "division + triang.")
  div_sweep,    // the same lambdas, naive plane sweep (paper Table "division + plane-sweep")
  norm_tri,     // division model on normalized coordinates, undistort, DLT
  norm_direct,  // the same lambdas, Eq. 10 directly on distorted points, one SVD
  opencv,       // the OpenCV user path (recon/opencv_path.hpp): its own corners, undistortPoints, DLT
  kMethodCount
};
const char* method_name(Method m);

// The paper's P, D, R and, known here only, E: the 3D RMS error against the truth. NaN: not available.
struct Scores {
  double P = NAN, D = NAN, R = NAN, E = NAN;
  int valid = 0;  // points reconstructed
};

// One rendered view of a board, its detection in truth order (row-major over the inner grid).
struct View {
  std::vector<Eigen::Vector3d> truth_mm;  // left camera frame
  std::vector<Eigen::Vector2d> truth_left, truth_right;
  bool found = false;                                             // board detected in both eyes
  std::vector<Eigen::Vector2d> left_px, right_px;                 // detected (truth order)
  std::vector<bool> detected;                                     // both eyes have the corner
  std::array<std::vector<Eigen::Vector3d>, kMethodCount> points;  // per method, NaN where refused
  bool opencv_found = false;                                      // the OpenCV path found both grids
  std::vector<Eigen::Vector2d> opencv_left, opencv_right;         // its corners (truth order)
  std::array<Scores, kMethodCount> scores;
};

struct Dataset {
  sim::Preset preset;
  recon::StereoRig rig;
  recon::BoardGeometry board;
  std::vector<View> views;
  int found = 0, opencv_found = 0;
  // lambda, lambda' from the plane homographies of the found views (paper Eq. 8-9), both variants.
  recon::DivisionLambdas lambdas_pixel, lambdas_normalized;
  std::array<Scores, kMethodCount> mean;  // over the found views
};

// Renders `views` board poses of the preset with the default (noisy) sensor and detects the corners with
// the daemon's detector (full search, no tracking).
Dataset render_dataset(const sim::Preset& preset, int views, std::uint64_t seed);
// Lambdas, every method on every found view, their scores and means.
// `lambda_source` (default: d itself) gives the views whose homographies fix the lambdas.
void run_methods(Dataset& d, const Dataset* lambda_source = nullptr);
// Our polynomial pipeline again on d's corners with d's rig: refined triangulation and board pose
// (after the corners or the rig changed).
void reconstruct_polynomial(Dataset& d, double corner_sigma_px);

// A copy of `clean` whose detected corners get Gaussian noise of sigma_px (each coordinate), reconstructed
// again by every method (lambdas re-estimated): what a classic corner detector would have given.
Dataset with_corner_noise(const Dataset& clean, double sigma_px, std::uint64_t seed);
inline constexpr double kClassicCornerSigmaPx = 0.2;

// The paper's "Distortion Models: Comparison": six points 2.189 mm apart projected noise-free with the
// polynomial rig, reconstructed by each method with the given dataset's homography lambdas.
struct SixPointRow {
  double P = NAN, D = NAN, R_own = NAN, R_true = NAN;
};
struct SixPointResult {
  std::string placement;                       // where the points are
  double offset_px = 0;                        // their centre's distance from the left principal point
  std::array<SixPointRow, kMethodCount> rows;  // poly_dlt and the division methods
};
std::vector<SixPointResult> six_point_comparison(const Dataset& d3);

struct FigureFiles {
  std::vector<std::string> png;  // relative to out_dir
};
FigureFiles write_figures(const std::vector<Dataset>& sets, const std::filesystem::path& out_dir);

struct StudyRun {
  StudyOptions options;
  std::vector<Dataset> sets;
  std::vector<Dataset> noisy;
  std::string cross_validation;  // the section's markdown (computed with the run)  // Dataset 3 with
                                 // kClassicCornerSigmaPx of corner noise (empty without it)
  std::vector<SixPointResult> six;
  FigureFiles figures;
  double seconds = 0;
};
void write_report(const StudyRun& run, const std::filesystem::path& file);
// Sections of the report with their own files: the cross-validation tables and "where we differ".
std::string cross_validation_section(const StudyRun& run, const Dataset& d3);
std::string differences_section(const StudyRun& run);

// Everything: render, reconstruct, plot, write out_dir/accuracy.md and out_dir/img/*.png.
StudyRun run_study(const StudyOptions& o);

}  // namespace naneye::tools::study
