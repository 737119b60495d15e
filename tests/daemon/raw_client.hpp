#pragma once
// A raw TCP client for the HTTP tests: it sends exactly the bytes it is given (malformed requests,
// one byte at a time, nothing at all) and reads with deadlines, so a server that stalls fails the
// test instead of hanging it.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace naneye::daemon::test {

// One HTTP/1.1 response read off a socket: status, headers block, body.
struct RawResponse {
  int status = 0;
  std::string head, body;
};

// The status code of a response's first line, 0 if it is not one.
inline int status_of(const std::string& response) {
  return response.rfind("HTTP/1.1 ", 0) == 0 && response.size() >= 12 ? std::stoi(response.substr(9, 3)) : 0;
}

class RawClient {
 public:
  using ms = std::chrono::milliseconds;
  static constexpr ms kTimeout{5000};  // longer than any answer the tests wait for, shorter than ctest's

  explicit RawClient(int port, in_addr_t addr = htonl(INADDR_LOOPBACK))
      : fd_(socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = addr;
    connected_ = connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawClient() { close(fd_); }
  RawClient(const RawClient&) = delete;
  RawClient& operator=(const RawClient&) = delete;

  bool connected() const { return connected_; }
  bool send(const std::string& s) {
    return ::send(fd_, s.data(), s.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(s.size());
  }

  // Everything the server sends until it closes or `timeout` has passed.
  std::string read_all(ms timeout = kTimeout) {
    std::string in;
    read_until(in, timeout, [](const std::string&) { return false; });
    return in;
  }
  // The status code of the first response line, 0 if none came within `timeout`.
  int status(ms timeout = kTimeout) {
    std::string in;
    read_until(in, timeout, [](const std::string& s) { return s.size() >= 12; });
    return status_of(in);
  }
  // Sends a GET and reads its whole response (by Content-Length); nullopt when the server closed
  // the connection first or sent no Content-Length.
  std::optional<RawResponse> get(const std::string& path, const std::string& headers = "") {
    if (!send("GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n" + headers + "\r\n")) return {};
    std::string in;
    std::size_t blank = std::string::npos, total = 0;
    bool bad = false;
    const bool complete = read_until(in, kTimeout, [&](const std::string& s) {
      if (blank == std::string::npos && (blank = s.find("\r\n\r\n")) != std::string::npos) {
        const auto cl = s.find("Content-Length: ");
        if (cl == std::string::npos || cl > blank) return bad = true;
        total = blank + 4 + std::stoull(s.substr(cl + 16));
      }
      return blank != std::string::npos && s.size() >= total;
    });
    if (!complete || bad) return {};
    return RawResponse{status_of(in), in.substr(0, blank), in.substr(blank + 4)};
  }
  // True when the server closes its side within `timeout` (recv sees the end of the stream).
  bool closed_by_server(ms timeout = kTimeout) {
    pollfd p{fd_, POLLIN, 0};
    char c;
    return poll(&p, 1, static_cast<int>(timeout.count())) > 0 && recv(fd_, &c, 1, 0) == 0;
  }

 private:
  // Appends what arrives to `in` until done(in), the server closes, or the deadline; true on done.
  template <class Done>
  bool read_until(std::string& in, ms timeout, Done done) {
    char buf[8192];
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (!done(in)) {
      const auto left = std::chrono::duration_cast<ms>(until - std::chrono::steady_clock::now());
      pollfd p{fd_, POLLIN, 0};
      if (left.count() <= 0 || poll(&p, 1, static_cast<int>(left.count())) <= 0) return false;
      const ssize_t n = recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) return false;
      in.append(buf, static_cast<std::size_t>(n));
    }
    return true;
  }

  int fd_;
  bool connected_ = false;
};

// `request` on a fresh connection to addr:port; everything until the server closes (or 5 s pass).
inline std::string round_trip(int port, const std::string& request, in_addr_t addr = htonl(INADDR_LOOPBACK)) {
  RawClient c(port, addr);
  if (!c.connected() || !c.send(request)) return {};
  return c.read_all();
}

}  // namespace naneye::daemon::test
