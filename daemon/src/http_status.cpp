// /v1/status, /healthz, /readyz.
#include <algorithm>
#include <cmath>

#include "http_access.hpp"
#include "http_internal.hpp"
#include "naneye/app/json_number.hpp"

namespace naneye::daemon::http {
namespace {

nlohmann::json latency_json(const LatencyRecorder::Snapshot& l) {
  return {{"p50", l.p50_ms}, {"p99", l.p99_ms}, {"max", l.max_ms}, {"samples", l.count}};
}

nlohmann::json counters_json(const driver::SourceCounters& c) {
  nlohmann::json j = nlohmann::json::object();
  driver::for_each_counter(c, [&j](const char* name, const char*, std::uint64_t v) { j[name] = v; });
  return j;
}

nlohmann::json scene_json(const PipelineStatus& s) {
  if (!s.scene) return nullptr;
  nlohmann::json depth = nullptr;
  if (const auto& d = s.scene->depth)
    depth = {{"valid_share", d->valid_share},
             {"median_mm", app::finite_or_null(d->median_mm)},
             {"calib_sigma_median_mm", app::finite_or_null(d->calib_sigma_median_mm)}};
  return {{"features", s.scene->features},
          {"valid_points", s.scene->valid_points},
          {"noise_sigma_dn", s.scene->noise_sigma_dn},
          {"depth", depth},
          {"pairs", s.scene_pairs},
          {"dense_pairs", s.dense_pairs}};
}

nlohmann::json reload_json(const std::optional<PipelineStatus::Reload>& r) {
  if (!r) return nullptr;
  return {{"ok", r->ok}, {"reason", r->reason}, {"uptime_s", r->at_uptime_s}};
}

// A SIGHUP's outcome for an access file; null when the settings name no such file.
nlohmann::json access_reload_json(bool configured, const AccessReloads& r) {
  if (!configured) return nullptr;
  return {
      {"reloads", r.reloads()}, {"reload_failures", r.failures()}, {"last_reload", reload_json(r.last())}};
}

// The folder (with its trailing '/') of a file:// URI's path, or empty.
std::string folder_of_uri(const std::string& uri) {
  constexpr std::string_view scheme = "file://";
  if (uri.compare(0, scheme.size(), scheme) != 0) return {};
  const std::string path = uri.substr(scheme.size(), uri.find('?') - scheme.size());
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

void strip_folders(nlohmann::json& j, const std::vector<std::string>& folders) {
  if (j.is_string()) {
    auto s = j.get<std::string>();
    for (const auto& f : folders)
      for (auto at = s.find(f); at != std::string::npos; at = s.find(f, at)) s.erase(at, f.size());
    j = std::move(s);
  } else if (j.is_structured()) {
    for (auto& v : j) strip_folders(v, folders);
  }
}

}  // namespace

void redact_paths(nlohmann::json& status, const HttpContext& ctx, const PipelineStatus& s) {
  // Every folder a status text can name: the calibration files', the sample capture's and the
  // source's. Removed wherever they occur (URIs, the fallback's reason, error texts), leaving the
  // file names, which say what is in use without mapping the machine.
  std::vector<std::string> folders;
  for (const auto& f : ctx.settings.calibration) folders.push_back(f.parent_path().string() + "/");
  // A refused token or certificate reload names its file.
  for (const auto* f :
       {&ctx.settings.http_token_file, &ctx.settings.http_tls_cert, &ctx.settings.http_tls_key})
    if (!f->empty()) folders.push_back(f->parent_path().string() + "/");
  if (!ctx.settings.sample_capture.empty())
    folders.push_back(ctx.settings.sample_capture.parent_path().string() + "/");
  for (const auto* uri : {&ctx.settings.source_uri, &s.choice.uri}) folders.push_back(folder_of_uri(*uri));
  if (s.info) folders.push_back(folder_of_uri(s.info->uri));
  std::erase_if(folders, [](const std::string& f) { return f.size() <= 1; });
  // Longest first, so that a folder inside another is not cut in half.
  std::sort(folders.begin(), folders.end(), [](const auto& a, const auto& b) { return a.size() > b.size(); });
  strip_folders(status, folders);
}

nlohmann::json status_json(const HttpContext& ctx, const PipelineStatus& s) {
  nlohmann::json source{
      {"requested", ctx.settings.source_uri},
      {"uri", s.info ? s.info->uri : s.choice.uri},
      {"kind", s.info ? nlohmann::json(s.info->kind) : nlohmann::json(nullptr)},
      {"device", s.info ? nlohmann::json(s.info->device) : nlohmann::json(nullptr)},
      {"live", s.info ? nlohmann::json(s.info->live) : nlohmann::json(nullptr)},
      {"nominal_fps", s.info ? nlohmann::json(s.info->nominal_fps) : nlohmann::json(nullptr)},
      {"state", s.source_state},
      {"error", s.source_error ? nlohmann::json(*s.source_error) : nlohmann::json(nullptr)},
      {"fallback", s.choice.fallback},
      {"reason", s.choice.reason},
      {"opens", s.source_opens},
      {"open_failures", s.source_open_failures}};
  nlohmann::json calib_files = nlohmann::json::array();
  for (const auto& f : ctx.settings.calibration) calib_files.push_back(f.string());
  const auto rig = ctx.pipeline->rig();
  return {{"state", to_string(s.state)},
          {"version", ctx.version},
          {"uptime_s", s.uptime_s},
          {"source", std::move(source)},
          {"fps", {{"left", s.fps_left}, {"right", s.fps_right}}},
          {"offset_ms", static_cast<double>(s.offset_ns) * 1e-6},
          {"counters", counters_json(s.counters)},
          {"pairs",
           {{"processed", s.pairs_processed},
            {"dropped", s.counters.pairs_dropped},
            {"publish_skipped", s.publish_skipped},
            {"superseded", s.pairs_superseded}}},
          {"recon_ms", latency_json(s.recon)},
          {"capture_to_publish_ms", latency_json(s.capture_to_publish)},
          {"last_result_age_ms",
           s.last_result_age_ms ? nlohmann::json(*s.last_result_age_ms) : nlohmann::json(nullptr)},
          {"processor", s.processor},
          {"recon_mode", app::to_string(ctx.settings.processor.mode)},
          {"scene", scene_json(s)},
          {"calibration",
           {{"files", calib_files},
            {"reloads", s.calibration_reloads},
            {"reload_failures", s.calibration_reload_failures},
            {"last_reload", reload_json(s.last_reload)},
            {"baseline_mm", rig->baseline_mm()}}},
          {"http",
           {{"connections", ctx.connections.connections.load()},
            {"connection_cap", ctx.connections.connection_cap},
            {"reading_heads", ctx.connections.reading_heads.load()},
            {"refused", ctx.connections.refused.load()},
            {"idle_evicted", ctx.connections.idle_evicted.load()},
            {"head_timeouts", ctx.connections.head_timeouts.load()},
            {"oversize", ctx.connections.oversize.load()},
            {"tls_failures", ctx.connections.tls_failures.load()},
            {"token", access_reload_json(!ctx.settings.http_token_file.empty(), ctx.token_reloads)},
            {"tls", access_reload_json(!ctx.settings.http_tls_cert.empty(), ctx.tls_reloads)}}},
          {"events",
           {{"clients", ctx.sse_clients.load()},
            {"clients_dropped", ctx.sse_dropped.load()},
            {"sent", ctx.sse_events.load()}}}};
}

void add_status_routes(httplib::Server& svr, HttpContext& ctx) {
  svr.Get("/v1/status", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    const auto s = ctx.pipeline->status();
    auto j = status_json(ctx, s);
    // Absolute paths tell a remote client how the machine is laid out: loopback clients only.
    if (!is_loopback(req.remote_addr)) redact_paths(j, ctx, s);
    send_json(res, j);
  });
  svr.Get("/healthz", [](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    send_json(res, {{"status", "alive"}});
  });
  svr.Get("/readyz", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    const auto s = ctx.pipeline->status();
    const double max_age = ctx.settings.max_result_age_ms;
    const bool fresh = s.last_result_age_ms && *s.last_result_age_ms <= max_age;
    if (s.state == ServiceState::streaming && fresh) {
      send_json(res, {{"status", "ready"},
                      {"state", to_string(s.state)},
                      {"last_result_age_ms", *s.last_result_age_ms}});
      return;
    }
    std::string why = "state is " + std::string(to_string(s.state));
    if (s.state == ServiceState::streaming) {
      why = "latest result is older than " + std::to_string(ctx.settings.max_result_age_ms) + " ms";
    }
    send_error(res, 503, "not_ready", why);
  });
  svr.Get("/metrics", [&ctx](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    set_body(res, metrics_text(ctx, ctx.pipeline->status()), "text/plain; version=0.0.4; charset=utf-8");
  });
}

}  // namespace naneye::daemon::http
