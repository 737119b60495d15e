#pragma once
// Who may ask naneyed anything (docs/http-api.md, "Access"), decided before routing:
//  - bound to loopback, a request whose Host is not the daemon's own name (127.0.0.1, localhost,
//    [::1], with its port) is refused: a web page whose DNS name was rebound to 127.0.0.1 would
//    otherwise read the camera through the visitor's browser;
//  - with http.token_file set, every request but /healthz presents the token, as
//    `Authorization: Bearer <token>` or as the session cookie that POST /v1/session hands out for
//    it (the browser viewer: EventSource and <img> cannot send headers). Tokens are compared as
//    SHA-256 digests with CRYPTO_memcmp, so the time taken says nothing about the token.
// The token file is read again on SIGHUP (reload_token); admit() may run on every HTTP thread
// meanwhile, so the token's digest and the session secret are read and replaced under a mutex.
#include <array>
#include <filesystem>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "http_internal.hpp"

namespace naneye::daemon::http {

using Digest = std::array<unsigned char, 32>;  // SHA-256

class Access {
 public:
  // Reads the token file when the settings name one; throws std::runtime_error naming the file
  // when it cannot be read or holds too short a token.
  explicit Access(const Settings& s);

  // The bound port (after bind): a Host header's port must be this one.
  void set_port(int port) { port_ = port; }
  bool token_required() const { return token_required_; }
  bool loopback_bind() const { return loopback_bind_; }

  // SIGHUP: reads `file` again, with the checks of the start. A refused file (unreadable, too short)
  // throws std::runtime_error naming it, and the token in use stays. A new token also ends every
  // session opened with the old one (a new session secret): a token is rotated because it may have
  // leaked, and so may the cookies it bought. Returns what was applied.
  std::string reload_token(const std::filesystem::path& file);

  // True when the request may be routed; otherwise `res` holds the refusal (403 or 401).
  bool admit(const httplib::Request& req, httplib::Response& res) const;
  // POST /v1/session: the token (form field `token`, or the Authorization header) for the cookie.
  void open_session(const httplib::Request& req, httplib::Response& res) const;

 private:
  bool token_matches(std::string_view presented) const;
  bool session_matches(std::string_view presented) const;
  bool host_allowed(std::string_view host) const;

  std::string bound_host_;
  bool loopback_bind_ = true;
  bool tls_ = false;
  int port_ = 0;
  bool token_required_ = false;  // fixed at start: a reload changes the token, not whether there is one
  mutable std::mutex mu_;        // guards the three below
  Digest token_digest_{};
  std::string session_;  // the cookie's value: random, for this run of the daemon (or token) only
  Digest session_digest_{};
};

// --check-config: the token file and the TLS certificate and key load as they would at start.
void check_access_files(const Settings& s, std::vector<std::string>& problems);

// 127.0.0.0/8, ::1, ::ffff:127.x.y.z, "localhost": the host names of this machine only.
bool is_loopback(std::string_view host);
// The Host header's name and port ("[::1]:8080" -> "::1", 8080; no port -> -1); false when malformed.
bool split_host(std::string_view header, std::string& name, int& port);

}  // namespace naneye::daemon::http
