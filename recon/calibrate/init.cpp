// The bundle's starting point. OpenCV's calibrateCamera (Zhang's closed form then its own LM) gives each
// eye's intrinsics and board poses; the bundle (calibrate/stereo.cpp) then estimates everything jointly
// with our CameraModel. Nothing here is the final estimate.
#include "naneye/recon/calibrate/bundle.hpp"
#include "naneye/recon/camera/rig.hpp"

// After Eigen (OpenCV's Eigen bridge requires it).
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace naneye::recon::bundle {
namespace {

struct EyeInit {
  Intrinsics intrinsics{};
  std::vector<bool> seen;  // per view
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> t;
};

bool init_eye(std::span<const CalibrationView> views, const BoardGeometry& board,
              const CalibrationSettings& s, int eye, EyeInit& out, std::string& error) {
  const char* name = eye == 0 ? "left" : "right";
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  out.seen.assign(views.size(), false);
  out.R.assign(views.size(), Eigen::Matrix3d::Identity());
  out.t.assign(views.size(), Eigen::Vector3d::Zero());
  for (std::size_t v = 0; v < views.size(); ++v) {
    const auto& corners = eye == 0 ? views[v].left : views[v].right;
    if (corners.size() < 4) continue;
    out.seen[v] = true;
    auto& o = object.emplace_back();
    auto& i = image.emplace_back();
    for (const BoardCorner& c : corners) {
      const Eigen::Vector3d P = board.corner(c.row, c.col);
      o.emplace_back(static_cast<float>(P.x()), static_cast<float>(P.y()), 0.0f);
      i.emplace_back(static_cast<float>(c.px.x()), static_cast<float>(c.px.y()));
    }
  }
  if (static_cast<int>(object.size()) < s.min_views_per_eye) {
    error = std::string("the ") + name + " eye saw the board in " + std::to_string(object.size()) +
            " views; at least " + std::to_string(s.min_views_per_eye) + " are needed";
    return false;
  }
  cv::Mat K = cv::Mat::eye(3, 3, CV_64F), D = cv::Mat::zeros(1, 5, CV_64F);
  int flags = 0;
  if (s.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (!s.tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  if (s.initial) {
    const CameraModel& cam = eye == 0 ? s.initial->left : s.initial->right;
    cv::eigen2cv(cam.K(), K);
    K.at<double>(0, 1) = 0.0;
    const Distortion& d = cam.distortion();
    D = (cv::Mat_<double>(1, 5) << d.k1, d.k2, s.tangential ? d.p1 : 0.0, s.tangential ? d.p2 : 0.0,
         s.fix_k3 ? 0.0 : d.k3);
    flags |= cv::CALIB_USE_INTRINSIC_GUESS;
  }
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    cv::calibrateCamera(object, image, cv::Size(s.image_width, s.image_height), K, D, rvecs, tvecs, flags,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  } catch (const cv::Exception& e) {
    error = std::string("initial guess for the ") + name + " eye failed (OpenCV: " + e.err + ")";
    return false;
  }
  if (!cv::checkRange(K) || !cv::checkRange(D) || K.at<double>(0, 0) <= 0 || K.at<double>(1, 1) <= 0) {
    error = std::string("initial guess for the ") + name + " eye is not a camera";
    return false;
  }
  const double* d = D.ptr<double>();
  out.intrinsics = {K.at<double>(0, 0),
                    K.at<double>(1, 1),
                    K.at<double>(0, 2),
                    K.at<double>(1, 2),
                    d[0],
                    d[1],
                    s.tangential ? d[2] : 0.0,
                    s.tangential ? d[3] : 0.0,
                    s.fix_k3 ? 0.0 : d[4]};
  std::size_t k = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (!out.seen[v]) continue;
    cv::Mat Rm;
    cv::Rodrigues(rvecs[k], Rm);
    cv::cv2eigen(Rm, out.R[v]);
    Eigen::Vector3d t;
    cv::cv2eigen(tvecs[k], t);
    out.t[v] = t;
    ++k;
  }
  return true;
}

}  // namespace

std::optional<State> initial_state(std::span<const CalibrationView> views, const BoardGeometry& board,
                                   const CalibrationSettings& settings, std::string& error) {
  EyeInit eyes[2];
  for (int eye = 0; eye < 2; ++eye)
    if (!init_eye(views, board, settings, eye, eyes[eye], error)) return std::nullopt;
  // The stereo pose from every view both eyes saw: Rs = Rr Rl^T, Ts = tr - Rs tl. The views agree to
  // a few milliradians, so the mean of their Rodrigues vectors is a fine starting point.
  Eigen::Vector3d om = Eigen::Vector3d::Zero(), T = Eigen::Vector3d::Zero();
  int both = 0;
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (!eyes[0].seen[v] || !eyes[1].seen[v]) continue;
    const Eigen::Matrix3d Rs = eyes[1].R[v] * eyes[0].R[v].transpose();
    om += rodrigues(Rs);
    T += eyes[1].t[v] - Rs * eyes[0].t[v];
    ++both;
  }
  if (both == 0) {
    error = "no view shows the board to both eyes: the stereo pose cannot be estimated";
    return std::nullopt;
  }
  State st;
  st.cam[0] = eyes[0].intrinsics;
  st.cam[1] = eyes[1].intrinsics;
  st.Rs = rodrigues(Eigen::Vector3d(om / both));
  st.Ts = T / both;
  st.Rb.resize(views.size());
  st.tb.resize(views.size());
  for (std::size_t v = 0; v < views.size(); ++v) {
    if (eyes[0].seen[v]) {
      st.Rb[v] = eyes[0].R[v];
      st.tb[v] = eyes[0].t[v];
    } else {  // right eye only: carry its pose into the left frame
      st.Rb[v] = st.Rs.transpose() * eyes[1].R[v];
      st.tb[v] = st.Rs.transpose() * (eyes[1].t[v] - st.Ts);
    }
  }
  return st;
}

}  // namespace naneye::recon::bundle
