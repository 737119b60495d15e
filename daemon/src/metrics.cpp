// /metrics in the Prometheus text exposition format 0.0.4.
#include <cmath>
#include <sstream>

#include "http_internal.hpp"

namespace naneye::daemon::http {
namespace {

void counter(std::ostringstream& os, const std::string& name, const std::string& help, std::uint64_t v) {
  os << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " counter\n" << name << ' ' << v << '\n';
}

void gauge(std::ostringstream& os, const std::string& name, const std::string& help, double v) {
  os << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " gauge\n" << name << ' ' << v << '\n';
}

void histogram(std::ostringstream& os, const std::string& name, const std::string& help,
               const LatencyRecorder::Snapshot& l) {
  os << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " histogram\n";
  std::uint64_t cumulative = 0;
  for (std::size_t b = 0; b < LatencyRecorder::kBounds.size(); ++b) {
    cumulative += l.buckets[b];
    os << name << "_bucket{le=\"" << LatencyRecorder::kBounds[b] << "\"} " << cumulative << '\n';
  }
  cumulative += l.buckets.back();
  os << name << "_bucket{le=\"+Inf\"} " << cumulative << '\n';
  os << name << "_sum " << l.sum_s << '\n' << name << "_count " << cumulative << '\n';
}

// Reloads on SIGHUP of one kind (calibration, token, certificate), as the calibration's first were.
void reloads(std::ostringstream& os, const std::string& prefix, const std::string& what,
             std::uint64_t applied, std::uint64_t refused,
             const std::optional<PipelineStatus::Reload>& last) {
  counter(os, prefix + "_reloads_total", what + " reloads applied (SIGHUP).", applied);
  counter(os, prefix + "_reload_failures_total", what + " reloads refused (the previous one stayed).",
          refused);
  gauge(os, prefix + "_last_reload_ok",
        "1: the latest reload was applied, 0: it was refused, -1: no reload yet.",
        last ? (last->ok ? 1.0 : 0.0) : -1.0);
}

}  // namespace

std::string metrics_text(const HttpContext& ctx, const PipelineStatus& s) {
  std::ostringstream os;
  os.precision(9);
  const auto& c = s.counters;
  counter(os, "naneye_pairs_processed_total", "Stereo pairs reconstructed by the worker.", s.pairs_processed);
  counter(os, "naneye_results_unpublished_total",
          "Results computed but not published because readers pinned every slot.", s.publish_skipped);
  counter(os, "naneye_pairs_superseded_total",
          "Live pairs not reconstructed because a newer pair was waiting behind them.", s.pairs_superseded);
  driver::for_each_counter(c, [&os](const char* name, const char* help, std::uint64_t v) {
    counter(os, std::string("naneye_source_") + name + "_total", help, v);
  });
  counter(os, "naneye_source_opens_total", "Times the source was opened.", s.source_opens);
  reloads(os, "naneye_calibration", "Calibration", s.calibration_reloads, s.calibration_reload_failures,
          s.last_reload);
  reloads(os, "naneye_http_token", "Bearer token (http.token_file)", ctx.token_reloads.reloads(),
          ctx.token_reloads.failures(), ctx.token_reloads.last());
  reloads(os, "naneye_http_tls", "TLS certificate and key", ctx.tls_reloads.reloads(),
          ctx.tls_reloads.failures(), ctx.tls_reloads.last());
  counter(os, "naneye_events_sent_total", "Server-sent events written to clients.", ctx.sse_events.load());
  counter(os, "naneye_events_clients_dropped_total", "Event-stream clients dropped for falling behind.",
          ctx.sse_dropped.load());
  gauge(os, "naneye_events_clients", "Open event-stream clients.", ctx.sse_clients.load());
  counter(os, "naneye_http_requests_total", "HTTP requests received (any path and status).",
          ctx.requests.load());
  const auto& h = ctx.connections;
  gauge(os, "naneye_http_connections", "Client connections open.", h.connections.load());
  gauge(os, "naneye_http_connection_cap", "Client connections kept open at most.", h.connection_cap);
  gauge(os, "naneye_http_reading_heads", "Client connections in the middle of a request head.",
        h.reading_heads.load());
  counter(os, "naneye_http_refused_total", "Connections answered 503 at the connection limit.",
          h.refused.load());
  counter(os, "naneye_http_idle_evicted_total", "Idle keep-alive connections closed to admit another.",
          h.idle_evicted.load());
  counter(os, "naneye_http_head_timeouts_total", "Requests not received within http.head_timeout_ms (408).",
          h.head_timeouts.load());
  counter(os, "naneye_http_oversize_total", "Requests refused for their size or framing (411/413/414/431).",
          h.oversize.load());
  counter(os, "naneye_http_tls_failures_total", "TLS handshakes that failed (bad client hello, not TLS).",
          h.tls_failures.load());
  counter(os, "naneye_depth_served_total", "Results served by /v1/depth (status 200).",
          ctx.depth_served.load());
  gauge(os, "naneye_sensor_fps_left", "Frame rate of the left sensor (its own clock).", s.fps_left);
  gauge(os, "naneye_sensor_fps_right", "Frame rate of the right sensor (its own clock).", s.fps_right);
  gauge(os, "naneye_pair_offset_seconds", "Right minus left timestamp of the latest pair.",
        static_cast<double>(s.offset_ns) * 1e-9);
  gauge(os, "naneye_last_result_age_seconds", "Age of the latest published result (-1 before the first).",
        s.last_result_age_ms ? *s.last_result_age_ms * 1e-3 : -1.0);
  gauge(os, "naneye_uptime_seconds", "Seconds since the service started.", s.uptime_s);
  os << "# HELP naneye_state The service state (1 for the current one).\n# TYPE naneye_state gauge\n";
  for (auto st : {ServiceState::starting, ServiceState::streaming, ServiceState::waiting_for_device,
                  ServiceState::stalled, ServiceState::stopped}) {
    os << "naneye_state{state=\"" << to_string(st) << "\"} " << (st == s.state ? 1 : 0) << '\n';
  }
  os << "# HELP naneye_build_info Version of the running naneyed.\n# TYPE naneye_build_info gauge\n"
     << "naneye_build_info{version=\"" << ctx.version << "\"} 1\n";
  counter(os, "naneye_scene_pairs_total", "Pairs the scene path ran on ([recon] mode scene or both).",
          s.scene_pairs);
  counter(os, "naneye_scene_valid_points_total", "Valid sparse scene points, summed over those pairs.",
          s.scene_valid_points);
  counter(os, "naneye_scene_dense_pairs_total", "Pairs with a dense depth map.", s.dense_pairs);
  if (s.scene) {
    // Absent (not 0) without a scene result: a gauge of 0 points would read as "nothing seen".
    gauge(os, "naneye_scene_features", "Sparse features tried on the latest pair.", s.scene->features);
    gauge(os, "naneye_scene_valid_points", "Valid sparse scene points of the latest pair.",
          s.scene->valid_points);
    gauge(os, "naneye_scene_noise_sigma_dn", "Image noise the latest pair's left frame measured (DN).",
          s.scene->noise_sigma_dn);
    if (s.scene->depth) {
      gauge(os, "naneye_scene_depth_valid_share",
            "Share of the pixels both eyes see that have a dense depth (latest pair).",
            s.scene->depth->valid_share);
      if (std::isfinite(s.scene->depth->median_mm))
        gauge(os, "naneye_scene_depth_median_mm", "Median dense depth of the latest pair (mm).",
              s.scene->depth->median_mm);
      if (std::isfinite(s.scene->depth->calib_sigma_median_mm))
        gauge(os, "naneye_scene_depth_calib_sigma_median_mm",
              "Median of the depth sigmas the calibration's covariance allows the latest dense map (mm).",
              s.scene->depth->calib_sigma_median_mm);
    }
  }
  histogram(os, "naneye_recon_duration_seconds", "Time the processing step took per pair.", s.recon);
  histogram(os, "naneye_capture_to_publish_seconds",
            "From the arrival of a pair's last record to the publication of its result.",
            s.capture_to_publish);
  return os.str();
}

}  // namespace naneye::daemon::http
