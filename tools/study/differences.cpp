// "Where we differ from the paper, and why": the report's closing section, its numbers from this run.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "format.hpp"
#include "naneye/recon/paper/division_fit.hpp"
#include "paper_tables.hpp"
#include "study.hpp"

namespace naneye::tools::study {
namespace {

// RMS corner error of naneye's detector or of the OpenCV path, both eyes.
double corner_rms(const Dataset& d, bool opencv_path) {
  double sq = 0;
  int n = 0;
  for (const View& v : d.views) {
    const bool found = opencv_path ? v.opencv_found : v.found;
    const auto& l = opencv_path ? v.opencv_left : v.left_px;
    const auto& r = opencv_path ? v.opencv_right : v.right_px;
    for (std::size_t i = 0; found && i < v.truth_left.size(); ++i) {
      sq += (l[i] - v.truth_left[i]).squaredNorm() + (r[i] - v.truth_right[i]).squaredNorm();
      n += 2;
    }
  }
  return n ? std::sqrt(sq / n) : NAN;
}

double worst(const Dataset& d, Method m, double Scores::*field) {
  double w = NAN;
  for (const View& v : d.views) {
    const double x = v.scores[static_cast<std::size_t>(m)].*field;
    if (v.found && std::isfinite(x) && !(x <= w)) w = x;
  }
  return w;
}

}  // namespace

std::string differences_section(const StudyRun& run) {
  std::ostringstream o;
  o << "## Where we differ from the paper, and why\n\n";
  const Dataset* d3 = nullptr;
  for (const Dataset& d : run.sets) {
    if (d.preset.name == "paper-d3") d3 = &d;
  }
  if (!d3) return o.str();
  const Scores& poly = d3->mean[poly_tri];
  const Scores& dlt = d3->mean[poly_dlt];
  const Scores& board = d3->mean[poly_board];
  const Scores& div = d3->mean[div_tri];
  const Scores& sweep = d3->mean[div_sweep];
  const Dataset* noisy = run.noisy.empty() ? nullptr : &run.noisy.front();
  const auto fit_l = recon::fit_division_to_camera(d3->rig.left, recon::DivisionVariant::image_centre, 4);
  const auto fit_r = recon::fit_division_to_camera(d3->rig.right, recon::DivisionVariant::image_centre, 4);

  o << "* **Renders, not photographs.** The paper measured real NanEye images of printed boards; we render "
       "them with the paper's own Dataset 3 calibration as the *true* camera. So our polynomial model is "
       "exact by construction and no calibration error enters the main tables (the paper's did; the "
       "cross-validation section is where calibration error shows). What is left is corner noise: "
       "naneye's detector measures the rendered corners to "
    << num(corner_rms(*d3, false), 3) << " px RMS on Dataset 3, the OpenCV path's detector to "
    << num(corner_rms(*d3, true), 3)
    << " px. Renders lack much of what real images add (print flatness, defocus across a tilted board, "
       "stray light, the sensor's fixed-pattern noise), and the paper used a classic corner finder. It gives "
       "no "
       "corner accuracy, but its figures say ~0.2 px: with 0.2 px of noise added to our corners the same "
       "views give P / D / R "
    << num(noisy ? noisy->mean[poly_dlt].P : NAN, 2) << " / " << num(noisy ? noisy->mean[poly_dlt].D : NAN, 2)
    << " / " << num(noisy ? noisy->mean[poly_dlt].R : NAN, 3)
    << " against the paper's 3.30 / 2.75 / 0.16 (mean of its five baseline planes).\n";
  o << "* **P and D of the baseline.** With naneye's corners the polynomial triangulation gives P "
    << num(dlt.P, 2) << " mm, D " << num(dlt.D, 2) << " mm (DLT, the paper's recipe) and P " << num(poly.P, 2)
    << ", D " << num(poly.D, 2)
    << " mm (our refined triangulation), some 25 times below the paper's: at 70 mm a 1 mm baseline turns a "
       "pixel of disparity into ~21 mm of depth (paper Eq. 2), so P and D measure the corner noise through "
       "that lever, linearly, and much less the model. The paper's own conclusion (\"reconstruction with "
       "higher accuracy requires ... jointly considering the radial distortion and the small baseline\") is "
       "what the board-pose rows do: fitting the known board to both eyes brings the 3D error from "
    << num(poly.E, 2) << " mm (triangulated) to " << num(board.E, 4)
    << " mm (with 0.2 px corners: " << num(noisy ? noisy->mean[poly_tri].E : NAN, 2) << " mm to "
    << num(noisy ? noisy->mean[poly_board].E : NAN, 3) << " mm).\n";
  o << "* **Division model, lambda from homographies.** With a ~1 mm baseline the homography between the two "
       "views of a board is close to the identity and a distortion common to both eyes cancels in it, so "
       "lambda is weakly observable (docs/division-model.md): the homographies give lambda = "
    << num(d3->lambdas_pixel.lambda_left, 2) << " / " << num(d3->lambdas_pixel.lambda_right, 2)
    << " px^-2 where the least-squares fit of one parameter to the true cameras is " << num(fit_l.lambda, 2)
    << " / " << num(fit_r.lambda, 2) << " px^-2, and even that best fit misses the polynomial by "
    << num(fit_l.max_px, 1) << " / " << num(fit_r.max_px, 1)
    << " px at the image edge (plot below). The paper saw the same weakness from the other side (\"the "
       "division model with a single coefficient can not correctly model this level of distortion\"). Here "
       "the division paths give E "
    << num(div.E, 2) << " mm (triangulation) against " << num(poly.E, 2)
    << " mm for the polynomial with the same corners. With 0.2 px corners the difference drowns in the noise "
       "(E "
    << num(noisy ? noisy->mean[div_tri].E : NAN, 2) << " against "
    << num(noisy ? noisy->mean[poly_dlt].E : NAN, 2)
    << " mm), as the paper's P and D for the division model stayed within a factor ~1.5 of its baseline. Its "
       "R, "
       "though, was 8 times worse for the division model (1.28 against 0.16 px on average); ours is not ("
    << num(noisy ? noisy->mean[div_tri].R : NAN, 3) << " against "
    << num(noisy ? noisy->mean[poly_dlt].R : NAN, 3)
    << " px, each reprojected with its own model). We do not know how the paper reprojected the division "
       "results.\n";
  o << "* **The OpenCV path.** The reconstruction a user would write with OpenCV (recon/opencv_path.hpp) "
       "gives E "
    << num(d3->mean[opencv].E, 2) << " mm on Dataset 3, against " << num(poly.E, 2)
    << " mm for naneye's triangulation on the same renders: the difference is the corners (above). It found "
    << d3->opencv_found << " of " << d3->views.size() << " boards, naneye's detector " << d3->found
    << " (a view where ours fails is missing from our rows, not counted as an error).\n";
  o << "* **Plane sweep = triangulation.** As in the paper (\"the plane-sweeping approach (as it was "
       "applied) "
       "is equivalent to triangulation\"): mean P / D / R "
    << num(div.P, 2) << " / " << num(div.D, 2) << " / " << num(div.R, 3) << " against " << num(sweep.P, 2)
    << " / " << num(sweep.D, 2) << " / " << num(sweep.R, 3) << ".\n";
  o << "* **The paper's blow-ups.** Its Plane 5 with normalized coordinates reached P = 833.587 mm, "
       "D = 1482 mm (and 26.6 / 42.8 mm directly with Eq. 10): a board reaching the image corners, where "
       "one parameter no longer follows the lens. Our worst view gives P "
    << num(worst(*d3, norm_tri, &Scores::P), 2) << " mm, D " << num(worst(*d3, norm_tri, &Scores::D), 2)
    << " mm (normalized + DLT) and P " << num(worst(*d3, norm_direct, &Scores::P), 2) << ", D "
    << num(worst(*d3, norm_direct, &Scores::D), 2)
    << " mm (Eq. 10): our renders keep every corner inside both images and inside the model's fold (the "
       "simulator's full-view poses), the paper's boards did not have to.\n";
  if (!run.six.empty()) {
    const SixPointResult& outer = run.six.back();
    o << "* **The six-point comparison and its 57 px R.** The paper does not say where its six points were. "
         "Near the axis the two eyes distort alike and the division model errs by micrometres; in the outer "
         "field ("
      << num(outer.offset_px, 0) << " px off-centre) D reaches " << num(outer.rows[div_tri].D, 2)
      << " mm, of the paper's 9.3 mm. Its R of 57-59 px is not reproduced: ours is "
      << num(outer.rows[div_tri].R_own, 2) << " px with the method's own model and "
      << num(outer.rows[div_tri].R_true, 2)
      << " px against the true camera. An R of 57 px is a quarter of the image; it would need a reprojection "
         "that mixes models (e.g. undistorted pinhole pixels compared with distorted ones); we do not know "
         "what "
         "the paper did. Its P of 0.006-0.008 mm (planar points, wrongly scaled) matches our placement near "
         "the axis.\n";
  }
  o << "* **Centre of distortion.** The paper's image-centre variant assumes the distortion is centred at "
       "(124.5, 124.5); the Dataset 3 left principal point lies "
    << num((Eigen::Vector2d(d3->rig.left.cx(), d3->rig.left.cy()) - Eigen::Vector2d(124.5, 124.5)).norm(), 1)
    << " px away. In our renders the principal point *is* the centre of distortion, so the normalized "
       "variant is the better-centred one (its best fit misses by less, docs/division-model.md).\n";
  o << "* **Which planes.** The paper shows 5 of its 19 images per table; we show the first 5 found views "
       "and "
       "the mean over all. They are not the same boards: compare ranges, not rows.\n";
  o << "* **Datasets 1 and 2.** The paper reconstructs only with Dataset 3; the summary adds our figures "
       "for the other two calibrations at their distances (20 and 50 mm), where depth from a 1 mm baseline "
       "is far better conditioned (Eq. 2: the error grows with Z^2, see the depth plot).";
  for (const Dataset& d : run.sets) {
    if (d.preset.name != "paper-d1") continue;
    o << " Their calibrations have k3 = 0, a profile one parameter can follow: on Dataset 1 the normalized "
         "division model comes close to the polynomial (E "
      << num(d.mean[norm_tri].E, 3) << " against " << num(d.mean[poly_tri].E, 3)
      << " mm), the image-centred one does not (" << num(d.mean[div_tri].E, 3)
      << " mm): there the centre of distortion matters more than the number of parameters.";
  }
  o << "\n\n";
  return o.str();
}

}  // namespace naneye::tools::study
