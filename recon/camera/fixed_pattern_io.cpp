#include "naneye/recon/camera/fixed_pattern_io.hpp"

#include <opencv2/core.hpp>
#include <stdexcept>

namespace naneye::recon {
namespace {

constexpr int kFormatVersion = 1;

void write_eye(cv::FileStorage& fs, const std::string& name, const FixedPattern& p) {
  fs << name << "{";
  fs << "width" << p.width << "height" << p.height;
  fs << "black_dn" << p.black_dn << "dark_frames" << p.dark_frames << "flat_frames" << p.flat_frames;
  fs << "dark_se_dn" << p.dark_se_dn << "gain_se" << p.gain_se << "dsnu_dn" << p.dsnu_dn << "prnu" << p.prnu;
  // The maps as matrices (copies: FileStorage writes cv::Mat, and this runs once per calibration).
  fs << "dark" << cv::Mat(p.height, p.width, CV_32FC1, const_cast<float*>(p.dark.data())).clone();
  if (!p.gain.empty())
    fs << "gain" << cv::Mat(p.height, p.width, CV_32FC1, const_cast<float*>(p.gain.data())).clone();
  fs << "}";
}

FixedPattern read_eye(const cv::FileNode& node, const std::string& file, const std::string& name) {
  auto fail = [&](const std::string& what) { return std::runtime_error(file + ": " + name + ": " + what); };
  if (node.empty() || !node.isMap()) throw fail("missing");
  FixedPattern p;
  p.width = static_cast<int>(node["width"]);
  p.height = static_cast<int>(node["height"]);
  p.black_dn = static_cast<float>(node["black_dn"]);
  p.dark_frames = static_cast<int>(node["dark_frames"]);
  p.flat_frames = static_cast<int>(node["flat_frames"]);
  p.dark_se_dn = static_cast<double>(node["dark_se_dn"]);
  p.gain_se = static_cast<double>(node["gain_se"]);
  p.dsnu_dn = static_cast<double>(node["dsnu_dn"]);
  p.prnu = static_cast<double>(node["prnu"]);
  if (p.width <= 0 || p.height <= 0 || p.width > 4096 || p.height > 4096) throw fail("bad width or height");
  auto read_map = [&](const char* key, std::vector<float>& out, bool required) {
    cv::Mat m;
    node[key] >> m;
    if (m.empty()) {
      if (required) throw fail(std::string("no '") + key + "' map");
      return;
    }
    if (m.type() != CV_32FC1 || m.rows != p.height || m.cols != p.width)
      throw fail(std::string("'") + key + "' is not a " + std::to_string(p.height) + " x " +
                 std::to_string(p.width) + " float map");
    if (!cv::checkRange(m)) throw fail(std::string("'") + key + "' holds NaN or infinity");
    out.assign(m.ptr<float>(), m.ptr<float>() + m.total());
  };
  read_map("dark", p.dark, true);
  read_map("gain", p.gain, false);
  for (float g : p.gain)
    if (!(g > 0)) throw fail("a gain <= 0");
  return p;
}

}  // namespace

void save_fixed_pattern(const std::filesystem::path& file, const StereoFixedPattern& pattern) {
  cv::FileStorage fs;
  try {
    fs.open(file.string(), cv::FileStorage::WRITE);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(file.string() + ": cannot write: " + e.what());
  }
  if (!fs.isOpened()) throw std::runtime_error(file.string() + ": cannot write");
  fs << "naneye_fixed_pattern" << kFormatVersion;
  write_eye(fs, "left", pattern.left);
  write_eye(fs, "right", pattern.right);
}

StereoFixedPattern load_fixed_pattern(const std::filesystem::path& file) {
  const std::string name = file.string();
  cv::FileStorage fs;
  try {
    fs.open(name, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(name + ": not a fixed-pattern file: " + e.what());
  }
  if (!fs.isOpened()) throw std::runtime_error(name + ": cannot read");
  if (static_cast<int>(fs["naneye_fixed_pattern"]) != kFormatVersion)
    throw std::runtime_error(name + ": not a naneye fixed-pattern file (version " +
                             std::to_string(kFormatVersion) + ")");
  StereoFixedPattern p{read_eye(fs["left"], name, "left"), read_eye(fs["right"], name, "right")};
  if (p.left.width != p.right.width || p.left.height != p.right.height)
    throw std::runtime_error(name + ": the eyes' maps differ in size");
  return p;
}

}  // namespace naneye::recon
