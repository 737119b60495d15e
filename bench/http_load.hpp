#pragma once
// A lean HTTP/1.1 load generator for bench_daemon: one thread, epoll, N keep-alive connections to
// 127.0.0.1, one request in flight per connection (no pipelining), every response read in full
// (Content-Length) and its latency recorded. It exists because a client on the same two cores as
// the server takes CPU from it: httplib's client threads cost about as much per request as the
// server; this one costs a send, a few recvs and a share of an epoll_wait per request. It sends no
// Accept-Encoding, like httplib's client and curl. Reconnects when the server closes a connection
// (its keep-alive request limit).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "thread_clock.hpp"

namespace naneye::bench {

struct LoadResult {
  std::uint64_t ok = 0;      // 200 responses
  std::uint64_t failed = 0;  // other statuses, malformed responses, connections lost mid-response
  std::uint64_t connects = 0;
  double seconds = 0;                     // wall time of the load
  double cpu_seconds = 0;                 // the load thread's own CPU time (user + system)
  std::vector<std::uint32_t> latency_ns;  // per 200 response, request written -> response complete

  double percentile_ms(double q) {
    if (latency_ns.empty()) return 0;
    const auto k = static_cast<std::size_t>(q * static_cast<double>(latency_ns.size() - 1));
    std::nth_element(latency_ns.begin(), latency_ns.begin() + static_cast<std::ptrdiff_t>(k),
                     latency_ns.end());
    return latency_ns[k] * 1e-6;
  }
};

namespace detail {

struct Connection {
  int fd = -1;
  std::string in;              // bytes of the response being read
  std::size_t header_end = 0;  // 0 until the blank line was seen
  std::size_t total = 0;       // header + body length once known
  int status = 0;
  bool close_after = false;
  std::chrono::steady_clock::time_point sent;
};

// Case-insensitive search of a header's value in the header block (short: a handful of lines).
inline std::string_view header_value(std::string_view head, std::string_view name) {
  for (std::size_t at = head.find("\r\n"); at != std::string_view::npos; at = head.find("\r\n", at + 2)) {
    const std::string_view line = head.substr(at + 2, head.find("\r\n", at + 2) - (at + 2));
    if (line.size() <= name.size() || line[name.size()] != ':') continue;
    bool same = true;
    for (std::size_t i = 0; i < name.size() && same; ++i) same = (line[i] | 0x20) == (name[i] | 0x20);
    if (!same) continue;
    std::string_view v = line.substr(name.size() + 1);
    while (!v.empty() && v.front() == ' ') v.remove_prefix(1);
    return v;
  }
  return {};
}

}  // namespace detail

inline LoadResult http_load(int port, const std::string& path, int connections, double seconds) {
  using clock = std::chrono::steady_clock;
  const std::string request = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  LoadResult r;
  r.latency_ns.reserve(static_cast<std::size_t>(seconds * 60000));
  const int ep = epoll_create1(0);
  std::vector<detail::Connection> conns(static_cast<std::size_t>(connections));

  auto send_request = [&](detail::Connection& c) {
    c.in.clear();
    c.header_end = c.total = 0;
    c.status = 0;
    c.close_after = false;
    c.sent = clock::now();
    return send(c.fd, request.data(), request.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(request.size());
  };
  auto open = [&](std::size_t i) {
    auto& c = conns[i];
    if (c.fd >= 0) close(c.fd);
    c.fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const int one = 1;
    setsockopt(c.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connect(c.fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return false;
    ++r.connects;
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u64 = i;
    epoll_ctl(ep, EPOLL_CTL_ADD, c.fd, &ev);
    return send_request(c);
  };

  const double cpu0 = thread_cpu_s();
  const auto t0 = clock::now();
  const auto until = t0 + std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(seconds));
  for (std::size_t i = 0; i < conns.size(); ++i) open(i);
  std::vector<epoll_event> events(conns.size());
  char buf[65536];
  while (clock::now() < until) {
    const int n = epoll_wait(ep, events.data(), static_cast<int>(events.size()), 10);
    for (int e = 0; e < n; ++e) {
      const auto i = static_cast<std::size_t>(events[static_cast<std::size_t>(e)].data.u64);
      auto& c = conns[i];
      const ssize_t got = recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
      if (got < 0 && (errno == EAGAIN || errno == EINTR)) continue;
      if (got <= 0) {  // closed by the server (keep-alive limit) or an error
        if (!c.in.empty()) ++r.failed;
        if (!open(i)) ++r.failed;
        continue;
      }
      c.in.append(buf, static_cast<std::size_t>(got));
      if (c.header_end == 0) {
        const auto blank = c.in.find("\r\n\r\n");
        if (blank == std::string::npos) continue;
        c.header_end = blank + 4;
        const std::string_view head(c.in.data(), blank);
        c.status = head.size() > 12 ? std::atoi(c.in.c_str() + 9) : 0;
        c.total =
            c.header_end +
            std::strtoull(std::string(detail::header_value(head, "Content-Length")).c_str(), nullptr, 10);
        c.close_after = detail::header_value(head, "Connection") == "close";
      }
      if (c.in.size() < c.total) continue;
      const auto took = clock::now() - c.sent;
      if (c.status == 200 && c.in.size() == c.total) {
        ++r.ok;
        r.latency_ns.push_back(static_cast<std::uint32_t>(std::min<std::int64_t>(
            std::chrono::duration_cast<std::chrono::nanoseconds>(took).count(), UINT32_MAX)));
      } else {
        ++r.failed;
      }
      if (c.close_after) {
        epoll_ctl(ep, EPOLL_CTL_DEL, c.fd, nullptr);
        if (!open(i)) ++r.failed;
      } else if (!send_request(c)) {
        ++r.failed;
        open(i);
      }
    }
  }
  r.seconds = std::chrono::duration<double>(clock::now() - t0).count();
  r.cpu_seconds = thread_cpu_s() - cpu0;
  for (auto& c : conns)
    if (c.fd >= 0) close(c.fd);
  close(ep);
  return r;
}

}  // namespace naneye::bench
