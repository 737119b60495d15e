#include "http_server.hpp"

#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

#include "http_access.hpp"
#include "http_gated_server.hpp"
#include "http_internal.hpp"
#include "http_transport.hpp"
#include "log.hpp"
#include "naneye/app/result_json.hpp"

namespace naneye::daemon {
namespace http {

void set_body(httplib::Response& res, std::string body, const char* content_type) {
  if (body.empty()) return res.set_content(body, content_type);
  // Given through a sized content provider: httplib compresses a set_content body on every request
  // whose client accepts br or gzip (browsers do), at brotli's default quality 11: ~12 ms of CPU for
  // a 15 kB /v1/depth, ~0.3 ms with gzip, against ~30 us to serve it as is. It never compresses a
  // sized provider's body, and the body is moved, not copied.
  auto shared = std::make_shared<const std::string>(std::move(body));
  const std::size_t size = shared->size();
  res.set_content_provider(size, content_type,
                           [shared](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             return sink.write(shared->data() + offset, length);
                           });
}

void send_json(httplib::Response& res, const nlohmann::json& body, int status) {
  res.status = status;
  // Client bytes are checked before any handler runs (reject_bad_encoding); `replace` is the last
  // line: nlohmann's default throws on invalid UTF-8, and an exception thrown from httplib's error
  // handler is not caught by httplib: it terminated the daemon on a request for "/%ff".
  set_body(res, body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

void send_error(httplib::Response& res, int status, const std::string& error, const std::string& detail) {
  send_json(res, {{"error", error}, {"detail", detail}}, status);
}

void send_fallback_error(httplib::Response& res) noexcept {
  // No allocation can be trusted here (the failure may be bad_alloc): a literal body, no provider.
  res.status = 500;
  res.body.assign(R"({"error":"internal_error","detail":"the error could not be reported"})");
  res.set_header("Content-Type", "application/json");
}

bool only_params(const httplib::Request& req, httplib::Response& res,
                 std::initializer_list<const char*> allowed) {
  for (const auto& [key, value] : req.params) {
    bool ok = false;
    for (const char* a : allowed) ok |= key == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      send_error(res, 400, "bad_parameter",
                 "unknown parameter \"" + key + "\"" +
                     (list.empty() ? "; this path takes none" : "; accepted: " + list));
      return false;
    }
    // Which of two values would count is a guess (proxies and frameworks differ): refuse both.
    if (req.params.count(key) > 1) {
      send_error(res, 400, "bad_parameter", "parameter \"" + key + "\" is given more than once");
      return false;
    }
  }
  return true;
}

bool int_param(const httplib::Request& req, httplib::Response& res, const char* name, std::int64_t lo,
               std::int64_t hi, std::optional<std::int64_t>& out) {
  if (!req.has_param(name)) return true;
  const std::string v = req.get_param_value(name);
  out = strict_int(v, lo, hi);
  if (!out || req.get_param_value_count(name) > 1) {
    send_error(res, 400, "bad_parameter",
               std::string(name) + " must be a decimal integer in " + std::to_string(lo) + ".." +
                   std::to_string(hi) + ", given once, got \"" + v + "\"");
    return false;
  }
  return true;
}

bool double_param(const httplib::Request& req, httplib::Response& res, const char* name,
                  std::optional<double>& out) {
  if (!req.has_param(name)) return true;
  const std::string v = req.get_param_value(name);
  out = strict_double(v);
  if (!out || req.get_param_value_count(name) > 1) {
    send_error(res, 400, "bad_parameter",
               std::string(name) + " must be a finite decimal number, given once, got \"" + v + "\"");
    return false;
  }
  return true;
}

bool reject_bad_encoding(const httplib::Request& req, httplib::Response& res) {
  const char* where = nullptr;
  if (!valid_utf8(req.path)) where = "the path";
  for (const auto& [key, value] : req.params)
    if (!where && (!valid_utf8(key) || !valid_utf8(value))) where = "a query parameter";
  for (const auto& [key, value] : req.headers)
    if (!where && (!valid_utf8(key) || !valid_utf8(value))) where = "a header";
  if (!where) return false;
  send_error(res, 400, "bad_encoding", std::string(where) + " is not valid UTF-8 (after percent-decoding)");
  return true;
}

std::shared_ptr<const std::string> result_json_text(HttpContext& ctx, const Published& p) {
  // Each HTTP thread first looks at its own copy of the pointer, so a thread takes the mutex once
  // per new result, not per request. The pool's threads belong to one server (httplib joins them
  // when it stops), so a thread never sees two contexts' sequence numbers.
  struct Local {
    std::uint64_t seq = 0;
    std::shared_ptr<const std::string> text;
  };
  thread_local Local local;
  if (local.text && local.seq == p.seq) return local.text;
  std::lock_guard lock(ctx.result_json_mutex);
  if (!ctx.result_json || ctx.result_json_seq != p.seq) {
    auto text = std::make_shared<const std::string>(app::result_to_json(p.result, p.scene).dump());
    // An event stream behind the latest result does not evict it.
    if (p.seq < ctx.result_json_seq) return text;
    ctx.result_json_seq = p.seq;
    ctx.result_json = std::move(text);
  }
  local = {p.seq, ctx.result_json};
  return local.text;
}

void append_with_age(std::string& out, double age_ms, const std::string& result_json) {
  const std::string age = nlohmann::json(age_ms).dump();
  out.reserve(out.size() + result_json.size() + age.size() + 10);
  out += "{\"age_ms\":";
  out += age;
  out += ',';
  out.append(result_json, 1);
}

namespace {

// The HTTP threads run at a lower priority than the pipeline: on two busy cores a burst of
// requests must not take the reconstruction worker's CPU and make a live source drop pairs. Raising
// a thread's nice value needs no privilege (the unit's sandbox allows it); it only matters when the
// cores are contended.
constexpr int kHttpNice = 5;

void lower_this_thread_priority() {
  // Linux: PRIO_PROCESS with a thread id sets that thread's nice value alone.
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), kHttpNice);
}

// Said at every start, loudly, because the unit's IPAddressAllow is the only other guard.
void warn_about_access(const Settings& s, const Access& access) {
  if (access.loopback_bind()) return;
  const auto log = daemon::log();
  if (!access.token_required()) {
    log->warn(
        "!!! http: serving {} beyond loopback WITHOUT A TOKEN: anyone who can reach port {} reads the "
        "camera and its depth; set http.token_file (docs/http-api.md, Access)",
        s.http_host, s.http_port);
  } else if (s.http_tls_cert.empty()) {
    log->warn(
        "http: serving {} beyond loopback without TLS: the token crosses the network in clear; set "
        "http.tls_cert and http.tls_key",
        s.http_host);
  }
}

}  // namespace

}  // namespace http

HttpServer::HttpServer(const Settings& settings, Pipeline& pipeline, std::string version)
    : ctx_(std::make_unique<HttpContext>()) {
  ctx_->settings = settings;
  ctx_->pipeline = &pipeline;
  ctx_->version = std::move(version);
  http::GateLimits limits;
  limits.max_connections = settings.http_max_connections;
  limits.head_timeout = std::chrono::milliseconds(settings.http_head_timeout_ms);
  limits.idle_timeout = std::chrono::milliseconds(settings.http_idle_timeout_ms);
  limits.threads = settings.http_threads;
  limits.nice = http::kHttpNice;
  // httplib closes a keep-alive connection after 5 requests by default: a client polling /v1/depth
  // then pays a TCP handshake, an accept and a hand-over every 5 requests (that halved the request
  // rate). An idle connection costs no thread (it waits in the gate), so 100 only bounds how long
  // one connection keeps its place.
  limits.keep_alive_max = 100;
  std::shared_ptr<const http::TlsContext> tls;  // null: plain HTTP; the gate keeps it
  if (!settings.http_tls_cert.empty())
    tls = std::make_shared<const http::TlsContext>(settings.http_tls_cert.string(),
                                                   settings.http_tls_key.string());
  access_ = std::make_unique<http::Access>(settings);
  http::warn_about_access(settings, *access_);
  server_ = http::make_gated_server(limits, ctx_->connections, std::move(tls), gate_);
  // Only for the Keep-Alive header httplib writes: the gate enforces both.
  server_->set_keep_alive_timeout(std::max<time_t>(1, settings.http_idle_timeout_ms / 1000));
  server_->set_keep_alive_max_count(static_cast<std::size_t>(limits.keep_alive_max));
  server_->set_payload_max_length(limits.max_body);
  server_->set_tcp_nodelay(true);
  // httplib listens with a backlog of 5 (compiled into Debian's library): when more connections
  // arrive at once while the accept thread waits for a core, the kernel drops their SYNs and each
  // client waits a second for its retransmission. bind() widens it; this notes the socket.
  server_->set_socket_options([this](socket_t sock) {
    httplib::default_socket_options(sock);
    listen_fd_ = sock;
  });
  // Counted before the handler runs, so that a client that got its answer also sees it counted.
  // Bad bytes first (nothing of them reaches a body), then who is asking (http_access.hpp).
  server_->set_pre_routing_handler(
      [ctx = ctx_.get(), access = access_.get()](const httplib::Request& req, httplib::Response& res) {
        ctx->requests.fetch_add(1, std::memory_order_relaxed);
        return http::reject_bad_encoding(req, res) || !access->admit(req, res)
                   ? httplib::Server::HandlerResponse::Handled
                   : httplib::Server::HandlerResponse::Unhandled;
      });
  server_->Post("/v1/session", [access = access_.get()](const httplib::Request& req, httplib::Response& res) {
    access->open_session(req, res);
  });
  http::add_status_routes(*server_, *ctx_);
  http::add_depth_routes(*server_, *ctx_);
  http::add_depth_map_routes(*server_, *ctx_);
  http::add_frame_routes(*server_, *ctx_);
  http::add_event_routes(*server_, *ctx_);
  http::add_web_routes(*server_);
  // Unmatched paths (and httplib's own errors) get the JSON error body too.
  // httplib calls the error handler outside its own try block (an exception there terminates the
  // process), and the exception handler inside a catch block: neither may throw.
  server_->set_error_handler([](const httplib::Request& req, httplib::Response& res) noexcept {
    if (res.has_header("Content-Type")) return;  // a handler's own error body
    try {
      if (res.status == 404) {
        http::send_error(res, 404, "not_found", "no resource at " + req.path + " (see docs/http-api.md)");
      } else {
        http::send_error(res, res.status, "http_error", "HTTP status " + std::to_string(res.status));
      }
    } catch (...) {
      http::send_fallback_error(res);
    }
  });
  server_->set_exception_handler(
      [](const httplib::Request& req, httplib::Response& res, std::exception_ptr ep) noexcept {
        try {
          std::string what = "unknown";
          try {
            if (ep) std::rethrow_exception(ep);
          } catch (const std::exception& e) {
            what = e.what();
          } catch (...) {
          }
          log()->error("handler for {} failed: {}", req.path, what);
          http::send_error(res, 500, "internal_error", what);
        } catch (...) {
          http::send_fallback_error(res);
        }
      });
}

HttpServer::~HttpServer() {
  stop(std::chrono::milliseconds(1000));
  if (thread_.joinable()) thread_.join();
}

int HttpServer::bind() {
  const auto& s = ctx_->settings;
  int port = s.http_port;
  if (port == 0) {
    port = server_->bind_to_any_port(s.http_host);
    if (port < 0) throw std::runtime_error("cannot bind an ephemeral port on " + s.http_host);
  } else if (!server_->bind_to_port(s.http_host, port)) {
    throw std::runtime_error("cannot bind " + s.http_host + ":" + std::to_string(port) +
                             " (in use, or the address is not local)");
  }
  // Linux updates the backlog of a socket that already listens.
  if (listen_fd_ >= 0) ::listen(listen_fd_, SOMAXCONN);
  access_->set_port(port);
  return port;
}

void HttpServer::start() {
  gate_->start();
  thread_ = std::thread([this] {
    http::lower_this_thread_priority();  // the accept loop
    server_->listen_after_bind();
    finished_.store(true);
  });
}

void HttpServer::reload_access(double uptime_s) {
  const auto& s = ctx_->settings;
  const auto log = daemon::log();
  if (access_->token_required()) {
    try {
      const std::string applied = access_->reload_token(s.http_token_file);
      log->info("SIGHUP: http.token_file {}", applied);
      ctx_->token_reloads.record(true, applied, uptime_s);
    } catch (const std::exception& e) {
      log->error("SIGHUP: token not reloaded, keeping the current one: {}", e.what());
      ctx_->token_reloads.record(false, e.what(), uptime_s);
    }
  }
  if (!s.http_tls_cert.empty()) {
    try {
      // Loaded and checked whole (chain, key, the key matching the certificate) before the gate
      // hands it to any connection.
      auto next = std::make_shared<const http::TlsContext>(s.http_tls_cert.string(), s.http_tls_key.string());
      const std::string applied = "applied: " + next->describe();
      gate_->set_tls(std::move(next));
      log->info("SIGHUP: TLS certificate {}", applied);
      ctx_->tls_reloads.record(true, applied, uptime_s);
    } catch (const std::exception& e) {
      log->error("SIGHUP: TLS certificate not reloaded, keeping the current one: {}", e.what());
      ctx_->tls_reloads.record(false, e.what(), uptime_s);
    }
  }
}

void AccessReloads::record(bool ok, std::string reason, double at_uptime_s) {
  (ok ? reloads_ : failures_).fetch_add(1);
  std::lock_guard lock(mu_);
  last_ = PipelineStatus::Reload{ok, std::move(reason), at_uptime_s};
}

std::optional<PipelineStatus::Reload> AccessReloads::last() const {
  std::lock_guard lock(mu_);
  return last_;
}

bool HttpServer::stop(std::chrono::milliseconds grace) {
  ctx_->stopping.store(true);
  if (server_) server_->stop();
  const auto until = std::chrono::steady_clock::now() + grace;
  while (thread_.joinable() && !finished_.load() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // Every connection is closed here, in-flight ones shut down first: nothing is left to wait for.
  if (gate_) gate_->stop();
  return !thread_.joinable() || finished_.load();
}

}  // namespace naneye::daemon
