#include "naneye/recon/camera/calibration_io.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <optional>
#include <sstream>

#include "calibration_yaml.hpp"

namespace naneye::recon {
namespace {

// A matrix entry together with the file it came from, so that errors can name the file.
struct Entry {
  cv::Mat value;
  std::string file;
};

using detail::Refusal;

std::nullopt_t refuse(Refusal& r, const std::string& file, const std::string& key,
                      const std::string& problem) {
  r.message = file + ": key '" + key + "': " + problem;
  return std::nullopt;
}

std::string shape_of(const cv::Mat& m) {
  std::ostringstream s;
  s << m.rows << "x" << m.cols;
  return s.str();
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

class Keys {
 public:
  explicit Keys(Refusal& r) : r_(r) {}

  bool read(const CalibrationText& t) {
    const std::string& file = t.name;
    auto keys = detail::read_calibration_yaml(file, t.text, r_);
    if (!keys) return false;
    for (detail::YamlKey& k : *keys) {
      if (k.value.empty()) {
        not_ours_.emplace(k.key, file + ": key '" + k.key + "': " + k.skipped);
        continue;
      }
      if (auto found = entries_.find(k.key); found != entries_.end()) {
        if (!same(found->second.value, k.value)) {
          refuse(r_, file, k.key, "given again with a different value (first in " + found->second.file + ")");
          return false;
        }
        continue;
      }
      entries_[k.key] = Entry{std::move(k.value), file};
    }
    return true;
  }

  const Entry* find(const std::string& key) const {
    auto it = entries_.find(key);
    return it == entries_.end() ? nullptr : &it->second;
  }

  // The entry, or null with the refusal set.
  const Entry* require(const std::string& key, const std::string& files) const {
    const Entry* e = find(key);
    if (e) return e;
    // Present but a string or a sequence: say so rather than "missing".
    if (auto it = not_ours_.find(key); it != not_ours_.end())
      r_.message = it->second + ", which is not a number or an opencv-matrix";
    else
      refuse(r_, files, key, "missing");
    return nullptr;
  }

  Refusal& refusal() const { return r_; }

 private:
  Refusal& r_;
  std::map<std::string, Entry> entries_;
  // Keys whose values are not numbers or matrices (the first occurrence of each): what require()
  // says, naming the file and the key, when one of them is needed.
  std::map<std::string, std::string> not_ours_;
};

bool finite(Refusal& r, const Entry& e, const std::string& key) {
  if (cv::checkRange(e.value)) return true;
  refuse(r, e.file, key, "contains a non-finite value");
  return false;
}

template <int Rows, int Cols>
std::optional<Eigen::Matrix<double, Rows, Cols>> to_eigen(Refusal& r, const Entry& e,
                                                          const std::string& key) {
  if (!finite(r, e, key)) return std::nullopt;
  cv::Mat m = e.value;
  // Vectors may be written as rows or as columns.
  if ((Rows == 1 || Cols == 1) && m.total() == static_cast<std::size_t>(Rows * Cols) &&
      (m.rows == 1 || m.cols == 1)) {
    m = m.reshape(1, Rows);
  }
  if (m.rows != Rows || m.cols != Cols) {
    std::ostringstream want;
    want << Rows << "x" << Cols;
    return refuse(r, e.file, key, "has shape " + shape_of(e.value) + ", expected " + want.str());
  }
  Eigen::Matrix<double, Rows, Cols> out;
  cv::cv2eigen(m, out);
  return out;
}

std::optional<Distortion> to_distortion(Refusal& r, const Entry& e, const std::string& key) {
  if (!finite(r, e, key)) return std::nullopt;
  const cv::Mat& m = e.value;
  if (!(m.rows == 1 || m.cols == 1))
    return refuse(r, e.file, key, "has shape " + shape_of(m) + ", expected 1x5");
  const std::size_t n = m.total();
  if (n == 8 || n == 12 || n == 14)
    return refuse(
        r, e.file, key,
        std::to_string(n) + " coefficients: only the 4- or 5-coefficient plumb_bob model is supported");
  if (n != 4 && n != 5)
    return refuse(r, e.file, key, "has " + std::to_string(n) + " coefficients, expected 5 (k1 k2 p1 p2 k3)");
  const double* v = m.ptr<double>();
  return Distortion{v[0], v[1], v[2], v[3], n == 5 ? v[4] : 0.0};
}

std::optional<CameraModel> to_camera(const Keys& keys, const std::string& mkey, const std::string& dkey,
                                     const std::string& files, int width, int height) {
  Refusal& r = keys.refusal();
  const Entry* me = keys.require(mkey, files);
  if (!me) return std::nullopt;
  const auto K = to_eigen<3, 3>(r, *me, mkey);
  if (!K) return std::nullopt;
  if (!((*K)(0, 0) > 0.0) || !((*K)(1, 1) > 0.0))
    return refuse(r, me->file, mkey, "focal lengths must be positive");
  if ((*K)(1, 0) != 0.0 || (*K)(2, 0) != 0.0 || (*K)(2, 1) != 0.0 || (*K)(2, 2) != 1.0)
    return refuse(r, me->file, mkey,
                  "not a camera matrix: the last row must be [0 0 1] and K(1,0) must be 0");
  const Entry* de = keys.require(dkey, files);
  if (!de) return std::nullopt;
  const auto d = to_distortion(r, *de, dkey);
  if (!d) return std::nullopt;
  return CameraModel(*K, *d, width, height);
}

std::optional<int> to_size(const Keys& keys, const std::string& key, const std::string& files) {
  Refusal& r = keys.refusal();
  const Entry* e = keys.require(key, files);
  if (!e || !finite(r, *e, key)) return std::nullopt;
  if (e->value.total() != 1) return refuse(r, e->file, key, "must be a single integer");
  const double v = e->value.at<double>(0);
  if (v != std::floor(v) || v < 1 || v > 100000) return refuse(r, e->file, key, "must be a positive integer");
  return static_cast<int>(v);
}

// An optional sigma: false (refused) if given but unusable; `out` stays empty if not given.
template <int Rows, int Cols>
bool optional_sigma(const Keys& keys, const std::string& key,
                    std::optional<Eigen::Matrix<double, Rows, Cols>>& out) {
  const Entry* e = keys.find(key);
  if (!e) return true;
  Refusal& r = keys.refusal();
  auto m = to_eigen<Rows, Cols>(r, *e, key);
  if (!m) return false;
  if ((m->array() < 0.0).any()) {
    refuse(r, e->file, key, "a standard deviation cannot be negative");
    return false;
  }
  out = *m;
  return true;
}

// The optional full covariance (kCalibrationParameters square, rig.hpp's order): refused unless it
// is symmetric and positive semi-definite to rounding, since a point's calibration sigma is a
// quadratic form in it and would otherwise come out negative or complex.
bool optional_covariance(const Keys& keys, std::optional<CalibrationCovariance>& out) {
  const std::string key = "calibration_covariance";
  const Entry* e = keys.find(key);
  if (!e) return true;
  Refusal& r = keys.refusal();
  auto m = to_eigen<kCalibrationParameters, kCalibrationParameters>(r, *e, key);
  if (!m) return false;
  const double scale = m->cwiseAbs().maxCoeff();
  if ((*m - m->transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) {
    refuse(r, e->file, key, "not symmetric");
    return false;
  }
  const CalibrationCovariance sym = 0.5 * (*m + m->transpose());
  const double smallest = Eigen::SelfAdjointEigenSolver<CalibrationCovariance>(sym).eigenvalues().minCoeff();
  // 1e-9 of the largest entry: the eigen-solver's own rounding on a matrix whose entries span
  // ~12 decades (k3's variance against om's), far below any real negative direction.
  if (smallest < -1e-9 * scale) {
    std::ostringstream s;
    s << "not positive semi-definite (smallest eigenvalue " << smallest << ")";
    refuse(r, e->file, key, s.str());
    return false;
  }
  out = sym;
  return true;
}

// The optional calibration_sigma_scale (CalibrationSigmas::covariance_scale): a single finite
// number >= 1, and only beside the covariance it scales.
bool optional_covariance_scale(const Keys& keys, const CalibrationSigmas& s, double& out) {
  const std::string key = "calibration_sigma_scale";
  const Entry* e = keys.find(key);
  if (!e) return true;
  Refusal& r = keys.refusal();
  if (!finite(r, *e, key)) return false;
  if (e->value.total() != 1) {
    refuse(r, e->file, key, "must be a single number");
    return false;
  }
  const double v = e->value.at<double>(0);
  if (!(v >= 1.0)) {
    refuse(r, e->file, key, "must be >= 1 (it only ever widens the covariance's sigmas)");
    return false;
  }
  if (!s.covariance) {
    refuse(r, e->file, key, "given without calibration_covariance, which it scales");
    return false;
  }
  out = v;
  return true;
}

// The whole file, refused once it is past what read_calibration_yaml takes (a pipe has no size
// to ask for, so it is read as it comes).
std::string read_text(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw CalibrationError(file + ": file not found");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CalibrationError(file + ": cannot be opened");
  std::string text;
  std::array<char, 16384> chunk;
  while (in && text.size() <= detail::kMaxCalibrationBytes) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    text.append(chunk.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw CalibrationError(file + ": cannot be read");
  return text;
}

}  // namespace

StereoRig load_rig(const std::vector<std::filesystem::path>& files) {
  std::vector<CalibrationText> texts;
  texts.reserve(files.size());
  for (const auto& f : files) texts.push_back(CalibrationText{f.string(), read_text(f)});
  return parse_rig(texts);
}

RigOrRefusal try_parse_rig(const std::vector<CalibrationText>& texts) {
  RigOrRefusal out;
  if (texts.empty()) {
    out.refusal = "no calibration file given";
    return out;
  }
  Refusal r;
  const auto refused = [&] {
    out.refusal = std::move(r.message);
    return std::move(out);
  };
  Keys keys(r);
  std::string names;
  for (const auto& t : texts) {
    if (!keys.read(t)) return refused();
    names += (names.empty() ? "" : " + ") + t.name;
  }
  const auto width = to_size(keys, "image_width", names);
  if (!width) return refused();
  const auto height = to_size(keys, "image_height", names);
  if (!height) return refused();

  StereoRig rig;
  auto left = to_camera(keys, "M1", "D1", names, *width, *height);
  if (!left) return refused();
  auto right = to_camera(keys, "M2", "D2", names, *width, *height);
  if (!right) return refused();
  rig.left = std::move(*left);
  rig.right = std::move(*right);

  const Entry* re = keys.require("R", names);
  if (!re) return refused();
  const auto R = to_eigen<3, 3>(r, *re, "R");
  if (!R) return refused();
  rig.R = *R;
  const double ortho = (rig.R.transpose() * rig.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (ortho > 1e-6 || rig.R.determinant() < 0.0) {
    std::ostringstream s;
    s << "not a rotation (|R^T R - I| = " << ortho << ", det = " << rig.R.determinant() << ")";
    refuse(r, re->file, "R", s.str());
    return refused();
  }
  const Entry* te = keys.require("T", names);
  if (!te) return refused();
  const auto T = to_eigen<3, 1>(r, *te, "T");
  if (!T) return refused();
  rig.T = *T;
  if (rig.T.norm() == 0.0) {
    refuse(r, te->file, "T", "zero baseline");
    return refused();
  }

  auto& s = rig.sigmas;
  if (!optional_sigma<3, 3>(keys, "M1_sigma", s.M1) || !optional_sigma<3, 3>(keys, "M2_sigma", s.M2) ||
      !optional_sigma<5, 1>(keys, "D1_sigma", s.D1) || !optional_sigma<5, 1>(keys, "D2_sigma", s.D2) ||
      !optional_sigma<3, 1>(keys, "om_sigma", s.om) || !optional_sigma<3, 1>(keys, "T_sigma", s.T) ||
      !optional_covariance(keys, s.covariance) || !optional_covariance_scale(keys, s, s.covariance_scale))
    return refused();
  out.rig = std::move(rig);
  return out;
}

StereoRig parse_rig(const std::vector<CalibrationText>& texts) {
  RigOrRefusal r = try_parse_rig(texts);
  if (!r.rig) throw CalibrationError(r.refusal);
  return std::move(*r.rig);
}

void save_rig(const StereoRig& rig, const std::filesystem::path& file) {
  cv::FileStorage fs(file.string(), cv::FileStorage::WRITE);
  if (!fs.isOpened()) throw CalibrationError(file.string() + ": cannot be written");
  auto put = [&](const char* key, const auto& m) {
    cv::Mat cvm;
    cv::eigen2cv(Eigen::MatrixXd(m), cvm);
    fs << key << cvm;
  };
  fs << "image_width" << rig.left.width() << "image_height" << rig.left.height();
  put("M1", rig.left.K());
  put("D1", rig.left.distortion().opencv_order());
  put("M2", rig.right.K());
  put("D2", rig.right.distortion().opencv_order());
  put("R", rig.R);
  put("T", rig.T);
  const auto& s = rig.sigmas;
  if (s.M1) put("M1_sigma", *s.M1);
  if (s.D1) put("D1_sigma", Eigen::Matrix<double, 1, 5>(s.D1->transpose()));
  if (s.M2) put("M2_sigma", *s.M2);
  if (s.D2) put("D2_sigma", Eigen::Matrix<double, 1, 5>(s.D2->transpose()));
  if (s.om) put("om_sigma", *s.om);
  if (s.T) put("T_sigma", *s.T);
  if (s.covariance) {
    fs.writeComment(
        "The calibration's covariance; rows and columns: left fx fy cx cy k1 k2 p1 p2 k3, right the same, "
        "om (3), T (3, mm). Fixed parameters have zero rows.");
    put("calibration_covariance", *s.covariance);
    if (s.covariance_scale != 1.0) {
      fs.writeComment(
          "The factor its sigmas understate the calibration's errors by, measured by cross-validation "
          "when it was made (halves of the views against each other, docs/calibration.md); applied to every "
          "calibration "
          "sigma.");
      fs << "calibration_sigma_scale" << s.covariance_scale;
    }
  }
}

}  // namespace naneye::recon
