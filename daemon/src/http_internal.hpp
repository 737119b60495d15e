#pragma once
// Pieces shared by the handler files of the HTTP server (not installed, not public API).
// Eigen (through http_server.hpp) must come before httplib.h: httplib pulls in <resolv.h>, whose
// `_res` macro would rewrite Eigen's parameter names.
// clang-format off
#include "http_server.hpp"
#include <httplib.h>
// clang-format on

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace naneye::daemon::http {

// Every text body (JSON, /metrics): sent as is, never compressed (see http_server.cpp).
void set_body(httplib::Response& res, std::string body, const char* content_type);
// Every error body: {"error": code, "detail": human text}.
void send_error(httplib::Response& res, int status, const std::string& error, const std::string& detail);
void send_json(httplib::Response& res, const nlohmann::json& body, int status = 200);
// The answer of last resort when even building an error body threw: a fixed 500 that cannot fail.
void send_fallback_error(httplib::Response& res) noexcept;

// True when `s` is well-formed UTF-8 (RFC 3629).
bool valid_utf8(std::string_view s);
// Answers 400 "bad_encoding" and returns true when the (percent-decoded) path, a query parameter or
// a header is not UTF-8: such bytes must never reach a JSON body.
bool reject_bad_encoding(const httplib::Request& req, httplib::Response& res);

// Refuses (400) any query parameter not in `allowed` or given twice; true when the request may go on.
bool only_params(const httplib::Request& req, httplib::Response& res,
                 std::initializer_list<const char*> allowed);
// Decimal only: no space, no '+', no hex, nothing after the number; nullopt otherwise or when out of
// [lo, hi] (strict_int) or not finite (strict_double).
std::optional<std::int64_t> strict_int(std::string_view v, std::int64_t lo, std::int64_t hi);
std::optional<double> strict_double(std::string_view v);
// Parses an optional parameter (strictly, given once); on a bad value sends 400 naming it and
// returns false.
bool int_param(const httplib::Request& req, httplib::Response& res, const char* name, std::int64_t lo,
               std::int64_t hi, std::optional<std::int64_t>& out);
bool double_param(const httplib::Request& req, httplib::Response& res, const char* name,
                  std::optional<double>& out);

// result_to_json(p.result, p.scene).dump(), serialized once per result for every HTTP thread. nlohmann sorts
// keys, so a caller splices "age_ms" (the first key) in after the opening brace.
std::shared_ptr<const std::string> result_json_text(HttpContext& ctx, const Published& p);
// Appends that text to `out` with "age_ms" (formatted as nlohmann formats a double) as its first key.
void append_with_age(std::string& out, double age_ms, const std::string& result_json);

nlohmann::json status_json(const HttpContext& ctx, const PipelineStatus& s);
// Removes from every text of `status` the folders of the files it names (calibration, capture).
void redact_paths(nlohmann::json& status, const HttpContext& ctx, const PipelineStatus& s);
std::string metrics_text(const HttpContext& ctx, const PipelineStatus& s);

void add_status_routes(httplib::Server& svr, HttpContext& ctx);     // status, healthz, readyz, metrics
void add_depth_routes(httplib::Server& svr, HttpContext& ctx);      // depth, depth/at, points, points.ply
void add_depth_map_routes(httplib::Server& svr, HttpContext& ctx);  // depth.png, depth/colour.png

// Calls fn(result, map) on the latest result and, when it has a dense map still held, that map
// (nullptr otherwise), both pinned for the call. False before the first result.
template <typename Fn>
bool read_latest_with_map(const Pipeline& pipeline, Fn&& fn) {
  return pipeline.results().read_latest([&](const Published& p, std::uint64_t seq) {
    const DepthSlot* map = nullptr;
    if (p.scene.dense)
      pipeline.depth_maps().read_seq(seq, [&](const DepthSlot& d) {
        map = &d;
        fn(p, map);
      });
    if (!map) fn(p, static_cast<const DepthSlot*>(nullptr));
  });
}
void add_frame_routes(httplib::Server& svr, HttpContext& ctx);  // frames/left.png, right.png
void add_event_routes(httplib::Server& svr, HttpContext& ctx);  // events (SSE)
void add_web_routes(httplib::Server& svr);                      // the viewer: /, /web/*
// The page that trades the token for the viewer's session cookie (daemon/web/login.html).
void serve_login(httplib::Response& res);

}  // namespace naneye::daemon::http
