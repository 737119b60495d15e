#pragma once
// naneyed's HTTP API (docs/http-api.md) over cpp-httplib. Handlers only read what the pipeline
// publishes; none of them can make the pipeline wait.
#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/settings.hpp"

namespace httplib {
class Server;
}

namespace naneye::daemon {
namespace http {
class Access;
class Gate;
class TlsContext;
}  // namespace http

// The connection gate's figures (daemon/src/http_gate.hpp), read by /v1/status and /metrics.
struct HttpCounters {
  std::atomic<int> connections{0};              // client connections open now
  std::atomic<int> reading_heads{0};            // of them, in the middle of a request head now
  int connection_cap = 0;                       // the most it keeps open (http.max_connections, fd limit)
  std::atomic<std::uint64_t> refused{0};        // answered 503 at the connection limit
  std::atomic<std::uint64_t> idle_evicted{0};   // idle keep-alive connections closed for a newcomer
  std::atomic<std::uint64_t> head_timeouts{0};  // 408: request not received within http.head_timeout_ms
  std::atomic<std::uint64_t> oversize{0};       // 411/413/414/431/400 on the request's framing
  std::atomic<std::uint64_t> tls_failures{0};   // TLS handshakes that failed (not a timeout)
};

// What SIGHUP did to one of the access files (the token; the certificate and key), reported as the
// calibration's reload is (/v1/status http.token and http.tls, /metrics naneye_http_*_reload*).
class AccessReloads {
 public:
  void record(bool ok, std::string reason, double at_uptime_s);
  std::uint64_t reloads() const { return reloads_.load(); }
  std::uint64_t failures() const { return failures_.load(); }
  std::optional<PipelineStatus::Reload> last() const;

 private:
  std::atomic<std::uint64_t> reloads_{0}, failures_{0};
  mutable std::mutex mu_;  // guards last_
  std::optional<PipelineStatus::Reload> last_;
};

// Shared by the handlers; counters are read by /v1/status and /metrics.
struct HttpContext {
  Settings settings;
  Pipeline* pipeline = nullptr;
  std::string version;
  std::atomic<int> sse_clients{0};
  std::atomic<std::uint64_t> sse_dropped{0};
  std::atomic<std::uint64_t> sse_events{0};
  std::atomic<std::uint64_t> requests{0};      // every request routed, any path or status
  std::atomic<std::uint64_t> depth_served{0};  // /v1/depth answered 200
  std::atomic<bool> stopping{false};
  HttpCounters connections;
  AccessReloads token_reloads, tls_reloads;  // only with a token file, only with TLS
  // The JSON text of the latest result served, built once for all HTTP threads (/v1/depth and
  // /v1/events); only HTTP threads take the mutex, never the pipeline.
  std::mutex result_json_mutex;
  std::uint64_t result_json_seq = 0;
  std::shared_ptr<const std::string> result_json;
};

class HttpServer {
 public:
  HttpServer(const Settings& settings, Pipeline& pipeline, std::string version);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Loads the token and the TLS certificate (throws std::runtime_error naming the file).
  // Binds settings.http_host:http_port (0: ephemeral) and returns the port; throws on failure.
  int bind();
  // Serves on its own thread (the accept loop), a poll thread reading request heads and a pool of
  // settings.http_threads running handlers (daemon/src/http_gate.hpp).
  void start();
  // SIGHUP (the main thread): reads the token file and the certificate and key again, when the
  // settings name them, each checked as at start; a file that fails keeps the one in use. Each
  // outcome is logged and recorded in the context, stamped `uptime_s`.
  void reload_access(double uptime_s);
  // Closes the listening socket and ends event streams; waits up to `grace` for the server's
  // threads. False when connections were still open after it (the caller may exit anyway).
  bool stop(std::chrono::milliseconds grace);

  const HttpContext& context() const { return *ctx_; }

 private:
  std::unique_ptr<HttpContext> ctx_;
  // Outlives server_ (declared before it): its threads use it until it is destroyed.
  std::unique_ptr<http::Access> access_;
  std::unique_ptr<httplib::Server> server_;
  http::Gate* gate_ = nullptr;  // owned by server_
  std::thread thread_;
  std::atomic<bool> finished_{false};
  int listen_fd_ = -1;  // the listening socket httplib created, to widen its backlog
};

}  // namespace naneye::daemon
