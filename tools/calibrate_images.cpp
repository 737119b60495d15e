// Board views for `naneye calibrate --left ... --right ...`: image pairs saved by other software, of
// any size and often of a lens nobody has calibrated yet. Without a lens model the detector cannot
// test that a grid is a plane (a distorted plane is no homography in raw pixels), so the first round
// detects with that test off (every corner must still fit and alternate like a checkerboard), a
// calibration from those views models the lens, and the second round detects again with it and the
// plane test on: only those views are calibrated on.
#include "calibrate_images.hpp"

#include <limits>
#include <stdexcept>

#include "image_pairs.hpp"
#include "naneye/recon/corners/stereo_ids.hpp"

namespace naneye::tools {
recon::StereoRig pinhole_rig(int width, int height) {
  // Only a scale for the detector: without distortion it works in raw pixels and fx cancels; the
  // calibration starts from OpenCV's closed form, not from this. A horizontal baseline, right eye on
  // the right (+x), as stereo pairs are saved.
  Eigen::Matrix3d K;
  K << width, 0, (width - 1) / 2.0, 0, width, (height - 1) / 2.0, 0, 0, 1;
  recon::StereoRig rig;
  rig.left = rig.right = recon::CameraModel(K, recon::Distortion{0, 0, 0, 0, 0}, width, height);
  rig.T = Eigen::Vector3d(-1, 0, 0);
  return rig;
}

CollectedViews collect_image_views(const std::vector<std::pair<std::string, std::string>>& pairs,
                                   const recon::StereoRig& guess, recon::CornerSettings corners,
                                   bool lens_known, driver::ColorMode color, Progress& progress) {
  if (!lens_known)
    corners.max_homography_rms_px = corners.max_homography_worst_px = std::numeric_limits<double>::infinity();
  CollectedViews out;
  recon::CornerDetector detect_left(guess.left, corners), detect_right(guess.right, corners);
  recon::CornerResult left, right;
  driver::ImageSettings io;
  io.color = color;
  driver::Image10 li, ri;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    driver::read_image(pairs[i].first, io, li);
    driver::read_image(pairs[i].second, io, ri);
    for (const auto* im : {&li, &ri})
      if (im->width != guess.left.width() || im->height != guess.left.height())
        throw std::runtime_error((im == &li ? pairs[i].first : pairs[i].second) + ": " +
                                 std::to_string(im->width) + " x " + std::to_string(im->height) +
                                 " pixels, but the calibration is for " + std::to_string(guess.left.width()) +
                                 " x " + std::to_string(guess.left.height()));
    ++out.pairs;
    const bool l = detect_left.detect_full(image_view(li), left);
    const bool r = detect_right.detect_full(image_view(ri), right);
    if (!l && !r) {
      ++out.no_board;
      continue;
    }
    recon::CalibrationView v;
    if (l) v.left = corners_of(left);
    if (r) {
      // Without a lens model the epipolar test cannot number the right eye: both eyes keep the
      // detector's image-space order, which agrees unless the board's axes are near 45 degrees.
      bool keep = true;
      if (l && lens_known) {
        const auto check = recon::resolve_stereo_ids(guess, left, right);
        keep = check.status == recon::StereoIdStatus::consistent ||
               check.status == recon::StereoIdStatus::flipped_right;
        out.ambiguous += !keep;
      }
      if (keep) v.right = corners_of(right);
    }
    out.one_eye += v.left.empty() || v.right.empty();
    out.views.push_back(std::move(v));
    out.sources.push_back({pairs[i].first, i});
    progress.update(static_cast<double>(i + 1) / static_cast<double>(pairs.size()),
                    "detecting boards: " + std::to_string(out.pairs) + " pairs read, " +
                        std::to_string(out.views.size()) + " boards found");
  }
  progress.done("detected boards: " + std::to_string(out.views.size()) + " views in " +
                std::to_string(out.pairs) + " image pairs (" + std::to_string(out.no_board) +
                " without a full board in either eye)");
  return out;
}

}  // namespace naneye::tools
