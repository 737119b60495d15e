// /v1/depth, /v1/depth/at, /v1/points, /v1/points.ply.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "http_internal.hpp"
#include "naneye/app/json_number.hpp"
#include "naneye/app/result_json.hpp"
#include "naneye/base/clock.hpp"
#include "naneye/daemon/depth_at.hpp"
#include "naneye/recon/geometry/calibration_uncertainty.hpp"

namespace naneye::daemon::http {
namespace {

double age_ms(const Published& p) {
  return static_cast<double>(base::monotonic_ns() - p.published_ns) * 1e-6;
}

// The depth sigma the calibration allows at X: systematic, common to every depth of the pair (so
// not to be averaged away); null when the calibration file carries no covariance (the paper's
// files: marginal sigmas only, docs/scene.md "Calibration uncertainty").
nlohmann::json calibration_sigma_json(const recon::StereoRig& rig, const Eigen::Vector3d& X) {
  const auto u = recon::CalibrationUncertainty::of(rig);
  return u ? nlohmann::json(u->depth_sigma_mm(X)) : nlohmann::json(nullptr);
}

void no_result(httplib::Response& res) {
  send_error(res, 503, "no_result", "no stereo pair has been reconstructed yet");
}

}  // namespace

void add_depth_routes(httplib::Server& svr, HttpContext& ctx) {
  svr.Get("/v1/depth", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {"max_age_ms"})) return;
    std::optional<std::int64_t> max_age;
    if (!int_param(req, res, "max_age_ms", 0, 86'400'000, max_age)) return;
    double age = 0;
    std::shared_ptr<const std::string> text;
    const bool have = ctx.pipeline->results().read_latest([&](const Published& p, std::uint64_t) {
      age = age_ms(p);
      text = result_json_text(ctx, p);
    });
    if (!have) return no_result(res);
    if (max_age && age > static_cast<double>(*max_age)) {
      char detail[128];
      std::snprintf(detail, sizeof detail, "latest result is %.1f ms old, more than max_age_ms=%lld", age,
                    static_cast<long long>(*max_age));
      return send_error(res, 503, "stale_result", detail);
    }
    std::string body;
    append_with_age(body, age, *text);
    set_body(res, std::move(body), "application/json");
    ctx.depth_served.fetch_add(1, std::memory_order_relaxed);
  });

  svr.Get("/v1/depth/at", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {"u", "v"})) return;
    std::optional<double> u, v;
    if (!double_param(req, res, "u", u) || !double_param(req, res, "v", v)) return;
    if (!u || !v)
      return send_error(res, 400, "bad_parameter",
                        "u and v (left raw pixel, centres at integers) are required");
    const auto rig = ctx.pipeline->rig();
    const auto& cam = rig->left;
    if (*u < -0.5 || *v < -0.5 || *u > cam.width() - 0.5 || *v > cam.height() - 0.5) {
      return send_error(res, 422, "outside_image",
                        "pixel outside the " + std::to_string(cam.width()) + "x" +
                            std::to_string(cam.height()) + " sensor");
    }
    nlohmann::json body;
    DepthAt d;
    DenseDepthAt dense;
    bool has_dense = false, map_held = false;
    const bool have = read_latest_with_map(*ctx.pipeline, [&](const Published& p, const DepthSlot* map) {
      has_dense = p.scene.dense;
      map_held = map != nullptr;
      if (map) dense = dense_depth_at(cam, map->map, {*u, *v});
      d = depth_at(cam, p.result, {*u, *v});
      body["pair"] = p.result.pair;
      body["age_ms"] = age_ms(p);
    });
    if (!have) return no_result(res);
    if (has_dense && !map_held) {
      // Overtaken by newer maps between reading the result and its map: never another pair's map.
      return send_error(res, 503, "depth_map_gone", "the latest result's dense map was replaced; retry");
    }
    body["u"] = *u;
    body["v"] = *v;
    if (has_dense) {
      if (dense.status == DenseAtStatus::outside_model)
        return send_error(res, 422, "outside_model",
                          "the pixel lies beyond the fold of the distortion model: no ray maps to it");
      if (dense.status == DenseAtStatus::ok) {
        body["source"] = "dense";
        body["map_px"] = {dense.map_u, dense.map_v};
        body["xyz_mm"] = {dense.xyz_mm.x(), dense.xyz_mm.y(), dense.xyz_mm.z()};
        body["depth_mm"] = dense.depth_mm;
        body["depth_sigma_mm"] = dense.depth_sigma_mm;
        body["calib_sigma_mm"] = calibration_sigma_json(*rig, dense.xyz_mm);
        body["range_mm"] = dense.range_mm;
        return send_json(res, body);
      }
      // No trusted dense depth at this pixel: the board plane of the same pair answers if it can.
      if (d.status != DepthAtStatus::ok)
        return send_error(res, 422, "no_depth",
                          std::string("the dense map has no trusted depth at this pixel (no texture, "
                                      "occluded, inconsistent or unseen by the right eye) and the board "
                                      "plane gives none: ") +
                              to_string(d.status));
    }
    switch (d.status) {
      case DepthAtStatus::ok:
        break;
      case DepthAtStatus::outside_model:
        return send_error(res, 422, "outside_model",
                          "the pixel lies beyond the fold of the distortion model: no ray maps to it");
      case DepthAtStatus::no_convergence:
        return send_error(res, 422, "no_convergence", "the pixel's ray could not be computed (domain edge)");
      case DepthAtStatus::no_board:
        return send_error(res, 422, "no_board", "the latest pair has no board to intersect");
      default:
        return send_error(res, 422, "off_board",
                          std::string("the pixel's ray does not meet the board: ") + to_string(d.status));
    }
    body["source"] = "board_plane";
    body["xyz_mm"] = {d.xyz_mm.x(), d.xyz_mm.y(), d.xyz_mm.z()};
    body["depth_mm"] = d.depth_mm;
    body["depth_sigma_mm"] = d.depth_sigma_mm;
    body["calib_sigma_mm"] = calibration_sigma_json(*rig, d.xyz_mm);
    body["range_mm"] = d.range_mm;
    body["board_xy_mm"] = {d.board_xy_mm.x(), d.board_xy_mm.y()};
    send_json(res, body);
  });

  svr.Get("/v1/points", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    nlohmann::json body;
    const bool have = ctx.pipeline->results().read_latest([&](const Published& p, std::uint64_t) {
      const auto& r = p.result;
      body["pair"] = r.pair;
      body["age_ms"] = age_ms(p);
      body["board_found"] = r.board_found;
      nlohmann::json pts = nlohmann::json::array();
      for (int i = 0; i < r.point_count; ++i) {
        const auto& pt = r.points[static_cast<std::size_t>(i)];
        if (!pt.valid) continue;
        pts.push_back({{"id", pt.id},
                       {"row", pt.row},
                       {"col", pt.col},
                       {"xyz_mm", {pt.xyz_mm.x(), pt.xyz_mm.y(), pt.xyz_mm.z()}},
                       {"depth_sigma_mm", pt.depth_sigma_mm},
                       {"calib_sigma_mm", app::finite_or_null(pt.calib_sigma_mm)},
                       {"xyz_board_mm", {pt.xyz_board_mm.x(), pt.xyz_board_mm.y(), pt.xyz_board_mm.z()}}});
      }
      body["points"] = std::move(pts);
    });
    if (!have) return no_result(res);
    send_json(res, body);
  });

  svr.Get("/v1/points.ply", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {"which"})) return;
    const std::string which = req.has_param("which") ? req.get_param_value("which") : "triangulated";
    if (which != "triangulated" && which != "board" && which != "scene" && which != "all") {
      return send_error(res, 400, "bad_parameter",
                        "which must be triangulated, board, scene or all, got \"" + which + "\"");
    }
    const bool corners = which != "scene", scene = which == "scene" || which == "all";
    std::ostringstream vertices;
    vertices.precision(9);
    int count = 0;
    std::uint64_t pair = 0;
    const bool have = ctx.pipeline->results().read_latest([&](const Published& p, std::uint64_t) {
      pair = p.result.pair;
      for (int i = 0; corners && i < p.result.point_count; ++i) {
        const auto& pt = p.result.points[static_cast<std::size_t>(i)];
        if (!pt.valid) continue;
        const Eigen::Vector3d& x = which == "board" ? pt.xyz_board_mm : pt.xyz_mm;
        vertices << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
        ++count;
      }
      for (std::size_t i = 0; scene && p.scene.computed && i < p.scene.sparse.points.size(); ++i) {
        const auto& pt = p.scene.sparse.points[i];
        if (!pt.valid()) continue;
        vertices << pt.X.x() << ' ' << pt.X.y() << ' ' << pt.X.z() << '\n';
        ++count;
      }
    });
    if (!have) return no_result(res);
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\ncomment naneye pair " << pair << ", "
        << (which == "scene" ? "valid scene points"
            : which == "all" ? "triangulated corners and scene points"
                             : which + " corners")
        << ", left camera frame, millimetres\nelement vertex " << count
        << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
        << vertices.str();
    res.set_header("Content-Disposition", "inline; filename=\"naneye-" + std::to_string(pair) + ".ply\"");
    res.set_content(ply.str(), "application/x-ply");
  });
}

}  // namespace naneye::daemon::http
