// The gate (http_gate.hpp): admission and the connection cap, fixed refusals, the pool threads that
// run complete requests, and shutdown. Its poll thread is in http_gate_poll.cpp.
#include "http_gate.hpp"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "http_server.hpp"
#include "log.hpp"

namespace naneye::daemon::http {
namespace {

using Clock = std::chrono::steady_clock;

// Descriptors kept for everything that is not an HTTP client: the source (a USB device, a V4L2
// node or a capture file it may reopen), the log, the recorder, libusb's own and the runtime's
// (eventfds, pipes). The daemon uses ~30 at rest; 64 leaves room for the source to reopen its
// file while every client slot is taken (it failed for 25 s once descriptors ran out).
constexpr int kReservedFds = 64;

int descriptor_budget(int wanted) {
  rlimit rl{};
  if (getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return wanted;
  const long room = static_cast<long>(rl.rlim_cur) - kReservedFds - Gate::kAdmitSlack;
  return static_cast<int>(std::clamp<long>(room, 1, wanted));
}

}  // namespace

void lower_priority(int nice) {
  // Linux: PRIO_PROCESS with a thread id sets that thread's nice value alone; raising it needs no
  // privilege.
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice);
}

Gate::Gate(const GateLimits& limits, RequestRunner& runner, HttpCounters& counters,
           std::shared_ptr<const TlsContext> tls)
    : limits_(limits),
      runner_(runner),
      counters_(counters),
      tls_(std::move(tls)),
      cap_(descriptor_budget(limits.max_connections)) {
  counters_.connection_cap = cap_;
  if (cap_ < limits.max_connections) {
    log()->warn(
        "http: at most {} connections (http.max_connections {}), to keep {} descriptors of the "
        "limit for the source",
        cap_, limits.max_connections, kReservedFds);
  }
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw std::runtime_error("http: eventfd: " + std::string(std::strerror(errno)));
}

Gate::~Gate() {
  stop();
  if (wake_fd_ >= 0) ::close(wake_fd_);
}

void Gate::start() {
  poller_ = std::thread([this] { poll_loop(); });
  for (int i = 0; i < limits_.threads; ++i) workers_.emplace_back([this] { worker_loop(); });
}

void Gate::wake() {
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = ::write(wake_fd_, &one, sizeof one);
}

void Gate::refuse(Conn& c, int status, const char* error, const char* detail) {
  // One non-blocking write of a fixed answer, then close: a refused client costs no thread and no
  // wait. Best effort: a client that does not read it just sees the connection closed, and a TLS
  // client still in its handshake cannot be answered at all.
  const char* reason = status == 503   ? "Service Unavailable"
                       : status == 408 ? "Request Timeout"
                       : status == 411 ? "Length Required"
                       : status == 413 ? "Payload Too Large"
                       : status == 414 ? "URI Too Long"
                       : status == 431 ? "Request Header Fields Too Large"
                                       : "Bad Request";
  char body[256], msg[512];
  const int blen = std::snprintf(body, sizeof body, "{\"error\":\"%s\",\"detail\":\"%s\"}", error, detail);
  const int mlen = std::snprintf(msg, sizeof msg,
                                 "HTTP/1.1 %d %s\r\nContent-Type: application/json\r\nContent-Length: "
                                 "%d\r\nConnection: close\r\n%s\r\n%s",
                                 status, reason, blen, status == 503 ? "Retry-After: 1\r\n" : "", body);
  std::size_t put = 0;
  if (c.io->established()) c.io->write(msg, static_cast<std::size_t>(mlen), put);
  // Closing with unread bytes in the receive queue sends a RST, which can destroy the answer
  // before the client reads it (RFC 9112, section 9.6): read away what has already arrived first
  // (bounded: 256 KiB, a head's limit many times over).
  char sink[16384];
  for (int k = 0; k < 16 && ::recv(c.fd, sink, sizeof sink, MSG_DONTWAIT) > 0; ++k) {
  }
  close_conn(c);
}

void Gate::close_conn(Conn& c) {
  c.io->close_notify();
  ::shutdown(c.fd, SHUT_RDWR);
  ::close(c.fd);
  open_.fetch_sub(1);
  counters_.connections.fetch_sub(1, std::memory_order_relaxed);
}

void Gate::admit(int fd) {
  const int open = open_.fetch_add(1) + 1;
  counters_.connections.fetch_add(1, std::memory_order_relaxed);
  auto c = std::make_unique<Conn>();
  c->fd = fd;
  std::shared_ptr<const TlsContext> tls;
  {
    std::lock_guard lock(tls_mu_);
    tls = tls_;
  }
  c->io = std::make_unique<Transport>(fd, std::move(tls));
  if (stop_.load() || open > cap_ + kAdmitSlack) {
    counters_.refused.fetch_add(1, std::memory_order_relaxed);
    return refuse(*c, 503, "too_many_connections", "the server is at its connection limit; retry later");
  }
  c->since = Clock::now();
  // A new connection has until the head deadline to send its first request.
  c->idle = false;
  c->deadline = c->since + limits_.head_timeout;
  {
    std::lock_guard lock(mu_);
    incoming_.push_back(std::move(c));
  }
  wake();
}

void Gate::set_tls(std::shared_ptr<const TlsContext> tls) {
  std::lock_guard lock(tls_mu_);
  if (tls_ && tls) tls_ = std::move(tls);
}

void Gate::worker_loop() {
  lower_priority(limits_.nice);
  for (;;) {
    std::unique_ptr<Conn> c;
    {
      std::unique_lock lock(mu_);
      ready_cv_.wait(lock, [&] { return stop_.load() || !ready_.empty(); });
      if (ready_.empty()) return;
      c = std::move(ready_.front());
      ready_.pop_front();
    }
    bool keep = !stop_.load();
    while (keep) {
      const HeadInfo h = parse_head(c->buf, limits_);
      if (h.verdict != HeadInfo::Verdict::complete) break;  // a pipelined request not all here yet
      const std::size_t size = h.head_bytes + h.body_bytes;
      ++c->served;
      const bool close_after = c->served >= limits_.keep_alive_max || stop_.load();
      bool client_closes = false;
      keep = runner_.run(*c->io, std::string_view(c->buf).substr(0, size), close_after, client_closes,
                         limits_.write_timeout) &&
             !close_after && !client_closes && !c->eof;
      c->buf.erase(0, size);
    }
    {
      std::lock_guard lock(mu_);
      in_flight_.erase(c->fd);
    }
    if (!keep || stop_.load()) {
      close_conn(*c);
      continue;
    }
    c->idle = c->buf.empty();
    c->since = Clock::now();
    c->deadline = c->since + (c->idle ? limits_.idle_timeout : limits_.head_timeout);
    {
      std::lock_guard lock(mu_);
      incoming_.push_back(std::move(c));
    }
    wake();
  }
}

void Gate::stop() {
  if (stop_.exchange(true)) {
    if (poller_.joinable()) poller_.join();
    for (auto& t : workers_)
      if (t.joinable()) t.join();
    return;
  }
  {
    std::lock_guard lock(mu_);
    // Ends the reads and writes of requests in progress (an event stream, a slow reader): their
    // worker sees the error at once instead of after its write timeout.
    for (int fd : in_flight_) ::shutdown(fd, SHUT_RDWR);
    ready_cv_.notify_all();
  }
  wake();
  if (poller_.joinable()) poller_.join();
  for (auto& t : workers_)
    if (t.joinable()) t.join();
  std::lock_guard lock(mu_);
  for (auto& c : incoming_) close_conn(*c);
  incoming_.clear();
  for (auto& c : ready_) close_conn(*c);
  ready_.clear();
}

}  // namespace naneye::daemon::http
