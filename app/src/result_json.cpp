#include "naneye/app/result_json.hpp"

#include <cmath>
#include <stdexcept>

#include "naneye/app/json_number.hpp"

namespace naneye::app {
namespace {

template <typename V>
nlohmann::json vec(const V& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(v[i]);
  return a;
}

template <int N>
Eigen::Matrix<double, N, 1> to_vec(const nlohmann::json& j) {
  if (!j.is_array() || j.size() != N) {
    throw nlohmann::json::type_error::create(302, "expected an array of " + std::to_string(N) + " numbers",
                                             &j);
  }
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v[i] = j.at(i).get<double>();
  return v;
}

}  // namespace

nlohmann::json result_to_json(const recon::PairResult& r) {
  nlohmann::json j;
  j["pair"] = r.pair;
  j["t_left_ns"] = r.t_left_ns;
  j["t_right_ns"] = r.t_right_ns;
  j["board_found"] = r.board_found;
  const auto text = [](const char* s) { return s ? nlohmann::json(s) : nlohmann::json(nullptr); };
  j["reference"] = {{"left", text(r.reference_left)}, {"right", text(r.reference_right)}};
  nlohmann::json pts = nlohmann::json::array();
  for (int i = 0; i < r.point_count; ++i) {
    const auto& p = r.points[static_cast<std::size_t>(i)];
    nlohmann::json o{{"id", p.id}, {"row", p.row}, {"col", p.col}};
    // The raw pixels are what the detector saw, so they are given even for a point that could not
    // be used downstream (e.g. outside the distortion model's domain); the 3D values are not.
    o["left_px"] = vec(p.left_px);
    o["right_px"] = vec(p.right_px);
    o["xyz_mm"] = p.valid ? vec(p.xyz_mm) : nlohmann::json(nullptr);
    o["depth_sigma_mm"] = p.valid ? nlohmann::json(p.depth_sigma_mm) : nlohmann::json(nullptr);
    o["calib_sigma_mm"] = p.valid ? finite_or_null(p.calib_sigma_mm) : nlohmann::json(nullptr);
    o["xyz_board_mm"] = p.valid ? vec(p.xyz_board_mm) : nlohmann::json(nullptr);
    o["valid"] = p.valid;
    pts.push_back(std::move(o));
  }
  j["points"] = std::move(pts);
  if (r.board) {
    const auto& b = *r.board;
    nlohmann::json rot = nlohmann::json::array();
    for (int row = 0; row < 3; ++row) rot.push_back(vec(Eigen::Vector3d(b.rotation.row(row).transpose())));
    j["board"] = {{"rotation", rot},
                  {"translation_mm", vec(b.translation_mm)},
                  {"normal", vec(b.normal)},
                  {"distance_mm", b.distance_mm},
                  {"rms_px", b.rms_px}};
  } else {
    j["board"] = nullptr;
  }
  if (r.metrics) {
    j["metrics"] = {{"planarity_mm", r.metrics->planarity_mm},
                    {"distance_error_mm", r.metrics->distance_error_mm},
                    {"reprojection_px", r.metrics->reprojection_px}};
  } else {
    j["metrics"] = nullptr;
  }
  return j;
}

namespace {

// The static string of a reference-check outcome read back ("passed", "failed", "not_checked").
const char* reference_text(const nlohmann::json& j) {
  if (j.is_null()) return nullptr;
  const auto s = j.get<std::string>();
  for (const char* known : {"passed", "failed", "not_checked"})
    if (s == known) return known;
  throw std::invalid_argument("reference: \"" + s + "\" is not passed, failed or not_checked");
}

}  // namespace

nlohmann::json result_to_json(const recon::PairResult& r, const SceneResult& scene) {
  nlohmann::json j = result_to_json(r);
  if (scene.computed)
    j["scene"] = scene_to_json(scene.sparse, scene.dense ? std::optional(scene.depth) : std::nullopt);
  return j;
}

recon::PairResult result_from_json(const nlohmann::json& j) {
  recon::PairResult r;
  r.pair = j.at("pair").get<std::uint64_t>();
  r.t_left_ns = j.at("t_left_ns").get<std::int64_t>();
  r.t_right_ns = j.at("t_right_ns").get<std::int64_t>();
  r.board_found = j.at("board_found").get<bool>();
  if (const auto it = j.find("reference"); it != j.end()) {
    r.reference_left = reference_text(it->at("left"));
    r.reference_right = reference_text(it->at("right"));
  }
  const auto& pts = j.at("points");
  if (pts.size() > static_cast<std::size_t>(recon::kMaxCorners)) {
    throw std::invalid_argument("points: more than " + std::to_string(recon::kMaxCorners));
  }
  r.point_count = static_cast<int>(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto& o = pts[i];
    auto& p = r.points[i];
    p.id = o.at("id").get<int>();
    p.row = o.at("row").get<int>();
    p.col = o.at("col").get<int>();
    p.valid = o.at("valid").get<bool>();
    p.left_px = to_vec<2>(o.at("left_px"));
    p.right_px = to_vec<2>(o.at("right_px"));
    if (p.valid) {
      p.xyz_mm = to_vec<3>(o.at("xyz_mm"));
      p.depth_sigma_mm = o.at("depth_sigma_mm").get<double>();
      // Absent from results written before it existed; null without a calibration covariance.
      if (const auto c = o.find("calib_sigma_mm"); c != o.end() && !c->is_null())
        p.calib_sigma_mm = c->get<double>();
      p.xyz_board_mm = to_vec<3>(o.at("xyz_board_mm"));
    }
  }
  if (const auto& b = j.at("board"); !b.is_null()) {
    recon::BoardResult br;
    const auto& rot = b.at("rotation");
    for (int row = 0; row < 3; ++row) br.rotation.row(row) = to_vec<3>(rot.at(row)).transpose();
    br.translation_mm = to_vec<3>(b.at("translation_mm"));
    br.normal = to_vec<3>(b.at("normal"));
    br.distance_mm = b.at("distance_mm").get<double>();
    br.rms_px = b.at("rms_px").get<double>();
    r.board = br;
  }
  if (const auto& m = j.at("metrics"); !m.is_null()) {
    r.metrics =
        recon::MetricsResult{m.at("planarity_mm").get<double>(), m.at("distance_error_mm").get<double>(),
                             m.at("reprojection_px").get<double>()};
  }
  return r;
}

}  // namespace naneye::app
