// The Server that naneyed runs: httplib's, with its connection-per-thread hand-over replaced by
// the gate (http_gate.hpp). httplib still accepts, parses, routes and writes.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cstring>

#include "http_gated_server.hpp"

namespace naneye::daemon::http {
namespace {

// httplib's accept loop hands each socket to its task queue; this one runs the hand-over at once
// (GatedServer::process_and_close_socket only gives the socket to the gate).
class InlineQueue final : public httplib::TaskQueue {
 public:
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override {}
};

std::string ip_of(const sockaddr_storage& a, int& port) {
  char text[INET6_ADDRSTRLEN] = "";
  if (a.ss_family == AF_INET) {
    const auto& v4 = reinterpret_cast<const sockaddr_in&>(a);
    inet_ntop(AF_INET, &v4.sin_addr, text, sizeof text);
    port = ntohs(v4.sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto& v6 = reinterpret_cast<const sockaddr_in6&>(a);
    inet_ntop(AF_INET6, &v6.sin6_addr, text, sizeof text);
    port = ntohs(v6.sin6_port);
  }
  return text;
}

// One request the gate has fully received, as the httplib Stream that process_request parses: reads
// come from that buffer only (a handler never waits for client bytes), writes go to the connection
// (socket or TLS session), each within the write timeout.
class RequestStream final : public httplib::Stream {
 public:
  RequestStream(Transport& io, std::string_view request, std::chrono::milliseconds write_timeout)
      : io_(io), fd_(io.fd()), in_(request), write_timeout_(write_timeout) {}

  bool is_readable() const override { return pos_ < in_.size(); }
  bool is_writable() const override {
    pollfd p{fd_, POLLOUT, 0};
    const int r = ::poll(&p, 1, static_cast<int>(write_timeout_.count()));
    return r > 0 && !(p.revents & (POLLERR | POLLHUP));
  }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, in_.size() - pos_);
    std::memcpy(ptr, in_.data() + pos_, n);
    pos_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    return io_.write_all(ptr, size, write_timeout_) ? static_cast<ssize_t>(size) : -1;
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (getpeername(fd_, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip = ip_of(a, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    if (getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len) == 0) ip = ip_of(a, port);
  }
  socket_t socket() const override { return fd_; }

 private:
  Transport& io_;
  int fd_;
  std::string_view in_;
  std::size_t pos_ = 0;
  std::chrono::milliseconds write_timeout_;
};

}  // namespace

class GatedServer final : public httplib::Server, public RequestRunner {
 public:
  GatedServer(const GateLimits& limits, HttpCounters& counters, std::shared_ptr<const TlsContext> tls)
      : gate_(limits, *this, counters, std::move(tls)) {
    new_task_queue = [] { return new InlineQueue; };
  }
  Gate& gate() { return gate_; }

  bool run(Transport& io, std::string_view request, bool close_after, bool& client_closes,
           std::chrono::milliseconds write_timeout) override {
    RequestStream strm(io, request, write_timeout);
    return process_request(strm, close_after, client_closes, nullptr);
  }

 private:
  // Virtual in httplib::Server (private there too): called on the accept thread through InlineQueue.
  bool process_and_close_socket(socket_t sock) override {
    // Headers and body go out in separate writes: without TCP_NODELAY, Nagle waits for the
    // client's delayed ACK (tens of ms) before sending the body.
    int one = 1;
    setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    gate_.admit(sock);
    return true;
  }

  Gate gate_;
};

std::unique_ptr<httplib::Server> make_gated_server(const GateLimits& limits, HttpCounters& counters,
                                                   std::shared_ptr<const TlsContext> tls, Gate*& gate) {
  auto server = std::make_unique<GatedServer>(limits, counters, std::move(tls));
  gate = &server->gate();
  return server;
}

}  // namespace naneye::daemon::http
