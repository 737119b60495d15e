#include "calib_export.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <sstream>
#include <stdexcept>

namespace naneye::tools {
namespace {

std::string num(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

template <typename M>
std::string list(const M& m) {
  std::string out;
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) out += (out.empty() ? "" : ", ") + num(m(r, c));
  return out;
}

Eigen::Matrix<double, 1, 5> dist(const recon::CameraModel& cam) {
  return cam.distortion().opencv_order();
}

void check_representable(const recon::CameraModel& cam, const char* side) {
  // ROS, OpenCV and mrcal's OPENCV5 have no skew term.
  if (cam.K()(0, 1) != 0.0)
    throw std::runtime_error(std::string("the ") + side +
                             " camera has a skew term, which these formats cannot hold");
}

std::ofstream open_out(const std::filesystem::path& p) {
  std::ofstream out(p);
  if (!out) throw std::runtime_error(p.string() + ": cannot be written");
  return out;
}

void close_out(std::ofstream& out, const std::filesystem::path& p) {
  out.close();
  if (!out) throw std::runtime_error(p.string() + ": write failed");
}

}  // namespace

Rectification rectify(const recon::StereoRig& rig) {
  // Bouguet's method as cv::stereoRectify does it (calib3d/src/calibration.cpp): r_r = R^(-1/2) turns
  // each camera half way, wR then takes the half-turned baseline t = r_r T onto the x axis by the
  // smallest rotation; R1 = wR r_r^T, R2 = wR r_r give both cameras one orientation.
  const Eigen::AngleAxisd aa(rig.R);
  const Eigen::Matrix3d r_r = Eigen::AngleAxisd(-0.5 * aa.angle(), aa.axis()).toRotationMatrix();
  const Eigen::Vector3d t = r_r * rig.T;
  const int idx = std::abs(t.x()) > std::abs(t.y()) ? 0 : 1;  // horizontal or vertical stereo
  Eigen::Vector3d uu = Eigen::Vector3d::Zero();
  uu[idx] = t[idx] > 0 ? 1.0 : -1.0;
  const Eigen::Vector3d ww = t.cross(uu);
  Eigen::Matrix3d wR = Eigen::Matrix3d::Identity();
  if (ww.norm() > 0)
    wR = Eigen::AngleAxisd(std::acos(std::abs(t[idx]) / t.norm()), ww.normalized()).toRotationMatrix();
  Rectification out;
  out.R1 = wR * r_r.transpose();
  out.R2 = wR * r_r;
  const double tx = (wR * t)[idx];
  const double f = rig.left.K()(0, 0);
  const double cx = 0.5 * (rig.left.K()(0, 2) + rig.right.K()(0, 2));
  const double cy = 0.5 * (rig.left.K()(1, 2) + rig.right.K()(1, 2));
  out.P1 << f, 0, cx, 0, 0, f, cy, 0, 0, 0, 1, 0;
  out.P2 = out.P1;
  out.P2(idx, 3) = f * tx;
  out.Q << 1, 0, 0, -cx, 0, 1, 0, -cy, 0, 0, 0, f, 0, 0, -1.0 / tx, 0;
  return out;
}

std::vector<std::filesystem::path> export_ros(const recon::StereoRig& rig, const std::filesystem::path& dir) {
  const Rectification rect = rectify(rig);
  std::vector<std::filesystem::path> written;
  for (const bool left : {true, false}) {
    const auto& cam = left ? rig.left : rig.right;
    check_representable(cam, left ? "left" : "right");
    const auto p = dir / (left ? "left.yaml" : "right.yaml");
    auto out = open_out(p);
    // The layout camera_calibration_parsers writes (ROS camera_info YAML).
    out << "image_width: " << cam.width() << "\nimage_height: " << cam.height() << "\n"
        << "camera_name: naneye_" << (left ? "left" : "right") << "\n"
        << "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [" << list(cam.K()) << "]\n"
        << "distortion_model: plumb_bob\n"
        << "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [" << list(dist(cam)) << "]\n"
        << "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [" << list(left ? rect.R1 : rect.R2) << "]\n"
        << "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [" << list(left ? rect.P1 : rect.P2) << "]\n";
    close_out(out, p);
    written.push_back(p);
  }
  return written;
}

std::vector<std::filesystem::path> export_opencv(const recon::StereoRig& rig,
                                                 const std::filesystem::path& dir) {
  check_representable(rig.left, "left");
  check_representable(rig.right, "right");
  const Rectification rect = rectify(rig);
  const auto p = dir / "stereo.yml";
  cv::FileStorage fs(p.string(), cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw std::runtime_error(p.string() + ": cannot be written");
  const auto put = [&fs](const char* key, const auto& m) {
    cv::Mat c;
    cv::eigen2cv(Eigen::MatrixXd(m), c);
    fs << key << c;
  };
  fs << "image_width" << rig.left.width() << "image_height" << rig.left.height();
  put("M1", rig.left.K());
  put("D1", dist(rig.left));
  put("M2", rig.right.K());
  put("D2", dist(rig.right));
  put("R", rig.R);
  put("T", rig.T);
  put("R1", rect.R1);
  put("R2", rect.R2);
  put("P1", rect.P1);
  put("P2", rect.P2);
  put("Q", rect.Q);
  fs.release();
  return {p};
}

std::vector<std::filesystem::path> export_mrcal(const recon::StereoRig& rig,
                                                const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> written;
  for (const bool left : {true, false}) {
    const auto& cam = left ? rig.left : rig.right;
    check_representable(cam, left ? "left" : "right");
    const auto& K = cam.K();
    const auto D = dist(cam);
    // mrcal's extrinsics are rt_cam_ref: x_cam = R(r) x_ref + t, the reference being the left camera.
    const Eigen::Vector3d r = left ? Eigen::Vector3d::Zero() : recon::rodrigues(rig.R);
    const Eigen::Vector3d t = left ? Eigen::Vector3d::Zero() : rig.T;
    const auto p = dir / (left ? "left.cameramodel" : "right.cameramodel");
    auto out = open_out(p);
    out << "# naneye calib export (LENSMODEL_OPENCV5 holds k1 k2 p1 p2 k3 exactly); translation in mm\n"
        << "{\n    'lensmodel':  'LENSMODEL_OPENCV5',\n"
        << "    'intrinsics': [ " << num(K(0, 0)) << ", " << num(K(1, 1)) << ", " << num(K(0, 2)) << ", "
        << num(K(1, 2)) << ", " << list(D) << " ],\n"
        << "    'extrinsics': [ " << list(r.transpose()) << ", " << list(t.transpose()) << " ],\n"
        << "    'imagersize': [ " << cam.width() << ", " << cam.height() << " ],\n}\n";
    close_out(out, p);
    written.push_back(p);
  }
  return written;
}

}  // namespace naneye::tools
