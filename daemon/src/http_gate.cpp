#include "http_gate.hpp"

#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "naneye/daemon/http_server.hpp"

namespace naneye::daemon::http {
namespace {

using Clock = std::chrono::steady_clock;

// Descriptors kept for everything that is not an HTTP client: the source (a USB device, a V4L2
// node or a capture file it may reopen), the log, the recorder, libusb's own and the runtime's
// (eventfds, pipes). The daemon uses ~30 at rest; 64 leaves room for the source to reopen its
// file while every client slot is taken (it failed for 25 s once descriptors ran out).
constexpr int kReservedFds = 64;
// Connections accepted beyond the cap before the poll thread has had the chance to evict an idle
// one: past this the accept thread refuses on its own (bounds descriptors even if the poller lags).
constexpr int kAdmitSlack = 16;

std::shared_ptr<spdlog::logger> log() {
  auto l = spdlog::get("daemon");
  return l ? l : spdlog::default_logger();
}

bool iequals_prefix(std::string_view line, std::string_view name) {
  if (line.size() < name.size()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char a = line[i] >= 'A' && line[i] <= 'Z' ? static_cast<char>(line[i] + 32) : line[i];
    if (a != name[i]) return false;
  }
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

int descriptor_budget(int wanted) {
  rlimit rl{};
  if (getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return wanted;
  const long room = static_cast<long>(rl.rlim_cur) - kReservedFds - kAdmitSlack;
  return static_cast<int>(std::clamp<long>(room, 1, wanted));
}

// Linux: PRIO_PROCESS with a thread id sets that thread's nice value alone; raising it needs no
// privilege.
void lower_priority(int nice) {
  setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), nice);
}

}  // namespace

HeadInfo parse_head(std::string_view buf, const GateLimits& limits) {
  HeadInfo info;
  using V = HeadInfo::Verdict;
  const auto eol = buf.find('\n');
  if (eol == std::string_view::npos) {
    if (buf.size() > limits.max_request_line) info.verdict = V::line_too_long;
    return info;
  }
  if (eol > limits.max_request_line) {
    info.verdict = V::line_too_long;
    return info;
  }
  // Header lines up to the blank one (httplib's reader takes "\r\n" or a bare "\n").
  std::size_t pos = eol + 1;
  int headers = 0;
  std::optional<std::size_t> length;
  for (;;) {
    const auto next = buf.find('\n', pos);
    if (next == std::string_view::npos) {
      if (buf.size() > limits.max_head) info.verdict = V::head_too_large;
      return info;
    }
    if (next + 1 > limits.max_head) {
      info.verdict = V::head_too_large;
      return info;
    }
    const std::string_view line = buf.substr(pos, next - pos);
    pos = next + 1;
    if (line.empty() || line == "\r") break;
    if (++headers > limits.max_headers) {
      info.verdict = V::too_many_headers;
      return info;
    }
    if (iequals_prefix(line, "transfer-encoding:")) {
      info.verdict = V::chunked;
      return info;
    }
    if (iequals_prefix(line, "content-length:")) {
      const auto v = trim(line.substr(15));
      std::size_t n = 0;
      // Digits only, and a second Content-Length must agree (RFC 9112, section 6.3).
      if (v.empty() || v.size() > 12) {
        info.verdict = v.empty() ? V::bad_length : V::body_too_large;
        return info;
      }
      for (char c : v) {
        if (c < '0' || c > '9') {
          info.verdict = V::bad_length;
          return info;
        }
        n = n * 10 + static_cast<std::size_t>(c - '0');
      }
      if (length && *length != n) {
        info.verdict = V::bad_length;
        return info;
      }
      length = n;
    }
  }
  info.head_bytes = pos;
  info.body_bytes = length.value_or(0);
  if (info.body_bytes > limits.max_body) {
    info.verdict = V::body_too_large;
    return info;
  }
  if (buf.size() >= info.head_bytes + info.body_bytes) info.verdict = V::complete;
  return info;
}

Gate::Gate(const GateLimits& limits, RequestRunner& runner, HttpCounters& counters)
    : limits_(limits), runner_(runner), counters_(counters), cap_(descriptor_budget(limits.max_connections)) {
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

void Gate::refuse(int fd, int status, const char* error, const char* detail) {
  // One non-blocking write of a fixed answer, then close: a refused client costs no thread and no
  // wait. Best effort: a client that does not read it just sees the connection closed.
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
  [[maybe_unused]] const auto n =
      ::send(fd, msg, static_cast<std::size_t>(mlen), MSG_NOSIGNAL | MSG_DONTWAIT);
  // Closing with unread bytes in the receive queue sends a RST, which can destroy the answer
  // before the client reads it (RFC 9112, section 9.6): read away what has already arrived first
  // (bounded: 256 KiB, a head's limit many times over).
  char sink[16384];
  for (int k = 0; k < 16 && ::recv(fd, sink, sizeof sink, MSG_DONTWAIT) > 0; ++k) {
  }
  close_conn(fd);
}

void Gate::close_conn(int fd) {
  ::shutdown(fd, SHUT_RDWR);
  ::close(fd);
  open_.fetch_sub(1);
  counters_.connections.fetch_sub(1, std::memory_order_relaxed);
}

void Gate::admit(int fd) {
  const int open = open_.fetch_add(1) + 1;
  counters_.connections.fetch_add(1, std::memory_order_relaxed);
  if (stop_.load() || open > cap_ + kAdmitSlack) {
    counters_.refused.fetch_add(1, std::memory_order_relaxed);
    return refuse(fd, 503, "too_many_connections", "the server is at its connection limit; retry later");
  }
  auto c = std::make_unique<Conn>();
  c->fd = fd;
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

bool Gate::on_readable(Conn& c) {
  char chunk[4096];
  for (;;) {
    const ssize_t n = ::recv(c.fd, chunk, sizeof chunk, MSG_DONTWAIT);
    if (n == 0) {
      // The client closed its side; what it sent before may still be a whole request
      // (`printf 'GET ...' | nc -N`), answered before the connection closes.
      c.eof = true;
      return !c.buf.empty();
    }
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) break;
      if (errno == EINTR) continue;
      return false;
    }
    if (c.idle) {
      c.idle = false;
      c.deadline = Clock::now() + limits_.head_timeout;
    }
    c.buf.append(chunk, static_cast<std::size_t>(n));
    // Never hold more than one bounded request: the verdict below refuses anything larger.
    if (c.buf.size() > limits_.max_head + limits_.max_body) break;
  }
  return true;
}

void Gate::poll_loop() {
  lower_priority(limits_.nice);
  std::vector<pollfd> fds;
  fds.reserve(static_cast<std::size_t>(cap_) + kAdmitSlack + 1);
  conns_.reserve(fds.capacity());
  while (!stop_.load()) {
    {
      std::lock_guard lock(mu_);
      for (auto& c : incoming_) conns_.push_back(std::move(c));
      incoming_.clear();
    }
    // Over the cap (counting connections a worker holds: every one is a descriptor), the oldest
    // connection that has sent nothing (an idle keep-alive one, or one that connected and stayed
    // silent: an idle flood) makes room; when the newest is the only such one, or every other is
    // in the middle of a request, the newest is refused.
    while (open_.load() > cap_ && !conns_.empty()) {
      auto oldest = conns_.end();
      for (auto it = conns_.begin(); it != conns_.end(); ++it) {
        if ((*it)->buf.empty() && (oldest == conns_.end() || (*it)->since < (*oldest)->since)) oldest = it;
      }
      if (oldest != conns_.end() && oldest + 1 != conns_.end()) {
        counters_.idle_evicted.fetch_add(1, std::memory_order_relaxed);
        close_conn((*oldest)->fd);
        conns_.erase(oldest);
      } else {
        counters_.refused.fetch_add(1, std::memory_order_relaxed);
        refuse(conns_.back()->fd, 503, "too_many_connections",
               "the server is at its connection limit; retry later");
        conns_.pop_back();
      }
    }
    const auto now = Clock::now();
    auto next = now + std::chrono::milliseconds(200);
    fds.clear();
    fds.push_back({wake_fd_, POLLIN, 0});
    for (std::size_t i = 0; i < conns_.size();) {
      Conn& c = *conns_[i];
      if (now >= c.deadline) {
        if (!c.idle && !c.buf.empty()) {
          counters_.head_timeouts.fetch_add(1, std::memory_order_relaxed);
          refuse(c.fd, 408, "request_timeout", "the request was not received in time");
        } else {
          close_conn(c.fd);  // idle keep-alive (or a connection that never sent a byte)
        }
        conns_[i] = std::move(conns_.back());
        conns_.pop_back();
        continue;
      }
      next = std::min(next, c.deadline);
      fds.push_back({c.fd, POLLIN, 0});
      ++i;
    }
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next - now).count() + 1;
    const int r = ::poll(fds.data(), fds.size(), static_cast<int>(wait));
    if (r <= 0) continue;
    if (fds[0].revents & POLLIN) {
      std::uint64_t v;
      [[maybe_unused]] const auto n = ::read(wake_fd_, &v, sizeof v);
    }
    // fds[k + 1] is conns_[k]: nothing above changed conns_ since fds was built.
    std::vector<std::unique_ptr<Conn>> done;
    for (std::size_t k = conns_.size(); k-- > 0;) {
      if (!fds[k + 1].revents) continue;
      Conn& c = *conns_[k];
      bool keep = on_readable(c);
      bool dispatch = false;
      if (keep && !c.buf.empty()) {
        using V = HeadInfo::Verdict;
        const HeadInfo h = parse_head(c.buf, limits_);
        switch (h.verdict) {
          case V::incomplete:
            if (c.eof) {
              close_conn(c.fd);
              keep = false;
            }
            break;
          case V::complete:
            dispatch = true;
            break;
          case V::line_too_long:
            refuse(c.fd, 414, "uri_too_long", "the request line is longer than 8192 bytes");
            keep = false;
            break;
          case V::head_too_large:
          case V::too_many_headers:
            refuse(c.fd, 431, "headers_too_large", "the request head is over 16384 bytes or 64 headers");
            keep = false;
            break;
          case V::body_too_large:
            refuse(c.fd, 413, "payload_too_large", "request bodies are limited to 65536 bytes");
            keep = false;
            break;
          case V::chunked:
            refuse(c.fd, 411, "length_required", "chunked request bodies are not accepted");
            keep = false;
            break;
          case V::bad_length:
            refuse(c.fd, 400, "bad_request", "invalid Content-Length");
            keep = false;
            break;
        }
        if (!keep && h.verdict != V::incomplete) counters_.oversize.fetch_add(1, std::memory_order_relaxed);
      } else if (!keep) {
        close_conn(c.fd);
      }
      if (!keep || dispatch) {
        if (dispatch) done.push_back(std::move(conns_[k]));
        conns_[k] = std::move(conns_.back());
        conns_.pop_back();
      }
    }
    if (!done.empty()) {
      std::lock_guard lock(mu_);
      for (auto& c : done) {
        in_flight_.insert(c->fd);
        ready_.push_back(std::move(c));
      }
      ready_cv_.notify_all();
    }
  }
  for (auto& c : conns_) close_conn(c->fd);
  conns_.clear();
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
      keep = runner_.run(c->fd, std::string_view(c->buf).substr(0, size), close_after, client_closes,
                         limits_.write_timeout) &&
             !close_after && !client_closes && !c->eof;
      c->buf.erase(0, size);
    }
    {
      std::lock_guard lock(mu_);
      in_flight_.erase(c->fd);
    }
    if (!keep || stop_.load()) {
      close_conn(c->fd);
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
  for (auto& c : incoming_) close_conn(c->fd);
  incoming_.clear();
  for (auto& c : ready_) close_conn(c->fd);
  ready_.clear();
}

}  // namespace naneye::daemon::http
