#pragma once
// The front of naneyed's HTTP server: who gets a thread, and when.
//
// cpp-httplib 0.11.4 gives every accepted connection a pool thread for its whole life: while a
// client sends its request head one byte every 3 s (slowloris) or sits idle between keep-alive
// requests, that thread serves nobody else, and 8 such clients stopped all service. Its Server
// offers no cap on connections and no deadline for a whole request head (only a per-recv timeout,
// which a drip of bytes resets). So the gate takes over each accepted socket
// (Server::process_and_close_socket is virtual) and:
//  - reads request heads on one poll thread, costing no pool thread while a client is slow or idle;
//  - gives a connection to a pool thread only with a complete, bounded request (head and body) in
//    hand, so a handler never waits for client bytes; httplib parses and routes it
//    (Server::process_request, protected) from that buffer;
//  - gives the connection back to the poll thread between keep-alive requests;
//  - bounds the number of open connections (and so descriptors), closing the oldest connection that
//    has sent nothing (idle keep-alive, or silent) for a newcomer, or else answering it 503 at once;
//  - answers 408 when a head is not complete within its deadline, 414/431 for an oversize request
//    line or head, 413 for an oversize body, 411 for a chunked body;
//  - with TLS, runs each handshake on the poll thread too, non-blocking, under the same deadline
//    and cap (http_transport.hpp): a stalled handshake is one more slow client.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "http_transport.hpp"

namespace naneye::daemon {

struct HttpCounters;

namespace http {

struct GateLimits {
  int max_connections = 512;  // open client connections (the effective cap may be lower: fds)
  std::chrono::milliseconds head_timeout{2000};   // first byte of a request to its complete head + body
  std::chrono::milliseconds idle_timeout{5000};   // keep-alive wait for the next request
  std::chrono::milliseconds write_timeout{2000};  // one write of a response to the client
  std::size_t max_request_line = 8192;            // bytes; httplib's own CPPHTTPLIB_REQUEST_URI_MAX_LENGTH
  std::size_t max_head = 16384;                   // bytes of request line + headers
  int max_headers = 64;                           // header lines
  std::size_t max_body = 65536;                   // bytes; the API takes no bodies, this only bounds memory
  int keep_alive_max = 100;                       // requests per connection (see http_server.cpp)
  int threads = 8;                                // pool threads that run handlers
  int nice = 0;                                   // nice value of the gate's threads (see http_server.cpp)
};

// What a request head says about the bytes that follow it (parse_head).
struct HeadInfo {
  enum class Verdict {
    incomplete,
    complete,
    line_too_long,
    head_too_large,
    too_many_headers,
    body_too_large,
    chunked,
    bad_length
  };
  Verdict verdict = Verdict::incomplete;
  std::size_t head_bytes = 0;  // through the blank line
  std::size_t body_bytes = 0;  // Content-Length
};
// Looks at the start of `buf` (bytes received so far for one request). Pure: for the unit tests.
HeadInfo parse_head(std::string_view buf, const GateLimits& limits);

// Serves one buffered request; implemented by the Server subclass (it calls process_request).
class RequestRunner {
 public:
  virtual ~RequestRunner() = default;
  // `request` holds exactly one request (head + body). False: close the connection.
  virtual bool run(Transport& io, std::string_view request, bool close_after, bool& client_closes,
                   std::chrono::milliseconds write_timeout) = 0;
};

// Sets the calling thread's nice value (the gate's threads yield to the pipeline's).
void lower_priority(int nice);

class Gate {
 public:
  // Connections accepted beyond the cap before the poll thread has had the chance to evict an idle
  // one: past this the accept thread refuses on its own (bounds descriptors even if the poller lags).
  static constexpr int kAdmitSlack = 16;

  // `tls` null: plain HTTP; else every connection is a TLS session with that context.
  Gate(const GateLimits& limits, RequestRunner& runner, HttpCounters& counters,
       std::shared_ptr<const TlsContext> tls);
  ~Gate();
  Gate(const Gate&) = delete;
  Gate& operator=(const Gate&) = delete;

  // The cap in force: limits.max_connections, lowered to fit the descriptor limit.
  int connection_cap() const { return cap_; }

  void start();
  // Takes ownership of an accepted socket (httplib's accept thread); never blocks.
  void admit(int fd);
  // From any thread (SIGHUP): the context that connections accepted from now on get; connections
  // already open keep theirs. A gate without TLS stays without.
  void set_tls(std::shared_ptr<const TlsContext> tls);
  // Closes every connection (in-flight ones are shut down so that their writes end) and joins.
  void stop();

 private:
  struct Conn {
    int fd = -1;
    std::unique_ptr<Transport> io;
    std::string buf;          // bytes received and not yet served
    bool idle = true;         // between requests (no byte of the next one yet)
    bool eof = false;         // the client closed its side
    bool want_write = false;  // TLS: the next step waits for the socket to take bytes
    int served = 0;
    std::chrono::steady_clock::time_point deadline, since;
  };
  void poll_loop();
  void worker_loop();
  // Reads what `c` has; false when the connection is finished (closed or answered and closed).
  bool on_readable(Conn& c);
  void refuse(Conn& c, int status, const char* error, const char* detail);
  void close_conn(Conn& c);
  void wake();

  GateLimits limits_;
  RequestRunner& runner_;
  HttpCounters& counters_;
  std::mutex tls_mu_;  // guards tls_: the accept thread reads it, a reload replaces it
  std::shared_ptr<const TlsContext> tls_;
  int cap_;
  int wake_fd_ = -1;  // eventfd: admissions and returns from workers
  std::atomic<bool> stop_{false};
  std::atomic<int> open_{0};

  std::mutex mu_;  // guards incoming_, ready_, in_flight_
  std::condition_variable ready_cv_;
  std::vector<std::unique_ptr<Conn>> incoming_;  // admitted or returned, not yet seen by the poller
  std::deque<std::unique_ptr<Conn>> ready_;      // a complete request in buf, waiting for a thread
  std::set<int> in_flight_;                      // fds a worker holds

  std::vector<std::unique_ptr<Conn>> conns_;  // poll thread only
  std::thread poller_;
  std::vector<std::thread> workers_;
};

}  // namespace http
}  // namespace naneye::daemon
