// The gate's poll thread (http_gate.hpp): reads every waiting connection, judges each request head,
// hands complete requests to the pool, and closes what is over its deadline or over the cap.
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>

#include "http_gate.hpp"
#include "http_server.hpp"

namespace naneye::daemon::http {

using Clock = std::chrono::steady_clock;

namespace {

// Bytes the client sent that this thread has not read yet (or, for TLS, not yet taken into the
// handshake): such a connection is not idle, only not read yet, so the cap must not evict it.
bool has_unread_bytes(int fd) {
  char b;
  return ::recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT) > 0;
}

}  // namespace

bool Gate::on_readable(Conn& c) {
  // A TLS handshake goes step by step here, under the head deadline that runs from the accept: a
  // client that stalls it is one more slow client, closed at its deadline or evicted for a newcomer
  // (it has sent no request byte).
  if (!c.io->established()) {
    const Io h = c.io->handshake();
    c.want_write = h == Io::want_write;
    if (h == Io::want_read || h == Io::want_write) return true;
    if (h != Io::done) {
      counters_.tls_failures.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
  }
  char chunk[4096];
  for (;;) {
    std::size_t n = 0;
    const Io r = c.io->read(chunk, sizeof chunk, n);
    if (r == Io::closed) {
      // The client closed its side; what it sent before may still be a whole request
      // (`printf 'GET ...' | nc -N`), answered before the connection closes.
      c.eof = true;
      return !c.buf.empty();
    }
    if (r == Io::failed) return false;
    if (r != Io::done) {
      c.want_write = r == Io::want_write;  // TLS: a read that must first write (a key update)
      break;
    }
    c.want_write = false;
    if (c.idle) {
      c.idle = false;
      c.deadline = Clock::now() + limits_.head_timeout;
    }
    c.buf.append(chunk, n);
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
    // connection that has sent nothing, read or still in its socket (an idle keep-alive one, or one
    // that connected and stayed silent: an idle flood), makes room; when the newest is the only such
    // one, or every other is in the middle of a request, the newest is refused.
    while (open_.load() > cap_ && !conns_.empty()) {
      auto oldest = conns_.end();
      for (auto it = conns_.begin(); it != conns_.end(); ++it) {
        if ((*it)->buf.empty() && (oldest == conns_.end() || (*it)->since < (*oldest)->since) &&
            !has_unread_bytes((*it)->fd)) {
          oldest = it;
        }
      }
      if (oldest != conns_.end() && oldest + 1 != conns_.end()) {
        counters_.idle_evicted.fetch_add(1, std::memory_order_relaxed);
        close_conn(**oldest);
        conns_.erase(oldest);
      } else {
        counters_.refused.fetch_add(1, std::memory_order_relaxed);
        refuse(*conns_.back(), 503, "too_many_connections",
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
          refuse(c, 408, "request_timeout", "the request was not received in time");
        } else {
          close_conn(c);  // idle keep-alive (or a connection that never sent a byte)
        }
        conns_[i] = std::move(conns_.back());
        conns_.pop_back();
        continue;
      }
      next = std::min(next, c.deadline);
      fds.push_back({c.fd, static_cast<short>(c.want_write ? POLLOUT : POLLIN), 0});
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
              close_conn(c);
              keep = false;
            }
            break;
          case V::complete:
            dispatch = true;
            break;
          case V::line_too_long:
            refuse(c, 414, "uri_too_long", "the request line is longer than 8192 bytes");
            keep = false;
            break;
          case V::head_too_large:
          case V::too_many_headers:
            refuse(c, 431, "headers_too_large", "the request head is over 16384 bytes or 64 headers");
            keep = false;
            break;
          case V::body_too_large:
            refuse(c, 413, "payload_too_large", "request bodies are limited to 65536 bytes");
            keep = false;
            break;
          case V::chunked:
            refuse(c, 411, "length_required", "chunked request bodies are not accepted");
            keep = false;
            break;
          case V::bad_length:
            refuse(c, 400, "bad_request", "invalid Content-Length");
            keep = false;
            break;
        }
        if (!keep && h.verdict != V::incomplete) counters_.oversize.fetch_add(1, std::memory_order_relaxed);
      } else if (!keep) {
        close_conn(c);
      }
      if (!keep || dispatch) {
        if (dispatch) done.push_back(std::move(conns_[k]));
        conns_[k] = std::move(conns_.back());
        conns_.pop_back();
      }
    }
    // Published once the reads above are judged: a connection counts from its first byte read to
    // its dispatch (what the cap cannot evict: a slowloris shows here).
    counters_.reading_heads.store(
        static_cast<int>(
            std::count_if(conns_.begin(), conns_.end(), [](const auto& c) { return !c->buf.empty(); })),
        std::memory_order_relaxed);
    if (!done.empty()) {
      std::lock_guard lock(mu_);
      for (auto& c : done) {
        in_flight_.insert(c->fd);
        ready_.push_back(std::move(c));
      }
      ready_cv_.notify_all();
    }
  }
  for (auto& c : conns_) close_conn(*c);
  conns_.clear();
}

}  // namespace naneye::daemon::http
