#include "http_access.hpp"

#include "http_transport.hpp"
#include "log.hpp"

#include <arpa/inet.h>
#include <openssl/crypto.h>
#include <openssl/rand.h>
#include <openssl/sha.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace naneye::daemon::http {
namespace {

// 16 bytes: a token shorter than that can be guessed by a client sending requests all day.
// `openssl rand -hex 32` (64 characters) is what docs/http-api.md suggests.
constexpr std::size_t kMinTokenBytes = 16;
// The session cookie: 32 random bytes, hex-encoded.
constexpr std::size_t kSessionBytes = 32;
constexpr std::string_view kCookieName = "naneye_session";

Digest sha256(std::string_view s) {
  Digest d{};
  SHA256(reinterpret_cast<const unsigned char*>(s.data()), s.size(), d.data());
  return d;
}

// Equal-length digests compared in time that does not depend on where they differ.
bool same(const Digest& a, const Digest& b) {
  return CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

std::string read_token(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("http.token_file " + file.string() + ": cannot be read");
  std::stringstream text;
  text << in.rdbuf();
  std::string t = text.str();
  // One line: the trailing newline an editor or `echo` adds is not part of the token.
  while (!t.empty() && (t.back() == '\n' || t.back() == '\r' || t.back() == ' ' || t.back() == '\t'))
    t.pop_back();
  if (t.size() < kMinTokenBytes || t.find_first_of(" \t\r\n") != std::string::npos)
    throw std::runtime_error("http.token_file " + file.string() + ": expected one token of at least " +
                             std::to_string(kMinTokenBytes) +
                             " characters without spaces (e.g. openssl rand -hex 32)");
  struct stat st {};
  if (::stat(file.c_str(), &st) == 0 && (st.st_mode & S_IROTH)) {
    log()->warn("http.token_file {} is readable by every user (mode {:o}): chmod 0640", file.string(),
                st.st_mode & 0777);
  }
  return t;
}

std::string hex(const unsigned char* p, std::size_t n) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) {
    s += digits[p[i] >> 4];
    s += digits[p[i] & 15];
  }
  return s;
}

std::string new_session_secret() {
  unsigned char secret[kSessionBytes];
  if (RAND_bytes(secret, sizeof secret) != 1) throw std::runtime_error("http: no random bytes for sessions");
  return hex(secret, sizeof secret);
}

// The value of one form field of an application/x-www-form-urlencoded body ('+' is a space).
std::string form_field(std::string_view body, std::string_view name) {
  while (!body.empty()) {
    const auto amp = body.find('&');
    const std::string_view item = body.substr(0, amp);
    if (item.size() > name.size() && item.substr(0, name.size()) == name && item[name.size()] == '=') {
      std::string out;
      const std::string_view v = item.substr(name.size() + 1);
      for (std::size_t i = 0; i < v.size(); ++i) {
        const auto nib = [](char c) {
          return c >= '0' && c <= '9'   ? c - '0'
                 : c >= 'a' && c <= 'f' ? c - 'a' + 10
                 : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                        : -1;
        };
        if (v[i] == '+') {
          out += ' ';
        } else if (v[i] == '%' && i + 2 < v.size() && nib(v[i + 1]) >= 0 && nib(v[i + 2]) >= 0) {
          out += static_cast<char>(nib(v[i + 1]) * 16 + nib(v[i + 2]));
          i += 2;
        } else {
          out += v[i];
        }
      }
      return out;
    }
    if (amp == std::string_view::npos) break;
    body.remove_prefix(amp + 1);
  }
  return {};
}

std::string_view bearer(const httplib::Request& req, std::string& storage) {
  storage = req.get_header_value("Authorization");
  // The scheme's name is case-insensitive (RFC 9110, section 11.1).
  constexpr std::string_view scheme = "bearer ";
  if (storage.size() <= scheme.size()) return {};
  for (std::size_t i = 0; i < scheme.size(); ++i) {
    const char c = storage[i] >= 'A' && storage[i] <= 'Z' ? static_cast<char>(storage[i] + 32) : storage[i];
    if (c != scheme[i]) return {};
  }
  return std::string_view(storage).substr(scheme.size());
}

std::string_view cookie(const std::string& header, std::string_view name) {
  std::string_view h(header);
  while (!h.empty()) {
    while (!h.empty() && (h.front() == ' ' || h.front() == ';')) h.remove_prefix(1);
    const auto end = h.find(';');
    const std::string_view item = h.substr(0, end);
    if (item.size() > name.size() && item.substr(0, name.size()) == name && item[name.size()] == '=')
      return item.substr(name.size() + 1);
    if (end == std::string_view::npos) break;
    h.remove_prefix(end + 1);
  }
  return {};
}

void unauthorized(const httplib::Request& req, httplib::Response& res) {
  res.set_header("WWW-Authenticate", "Bearer realm=\"naneyed\"");
  // A browser opening the viewer gets the form that trades the token for the session cookie.
  if (req.method == "GET" && req.path == "/") {
    serve_login(res);
    res.status = 401;
    return;
  }
  send_error(res, 401, "unauthorized",
             "this server needs its token: Authorization: Bearer <token> (or the viewer's session cookie)");
}

}  // namespace

void check_access_files(const Settings& s, std::vector<std::string>& problems) {
  try {
    Access access(s);
  } catch (const std::exception& e) {
    problems.push_back(e.what());
  }
  if (s.http_tls_cert.empty()) return;
  try {
    TlsContext tls(s.http_tls_cert.string(), s.http_tls_key.string());
  } catch (const std::exception& e) {
    problems.push_back(e.what());
  }
}

bool is_loopback(std::string_view host) {
  if (host == "localhost") return true;
  std::string h(host);
  in_addr a4{};
  if (inet_pton(AF_INET, h.c_str(), &a4) == 1) return (ntohl(a4.s_addr) >> 24) == 127;
  in6_addr a6{};
  if (inet_pton(AF_INET6, h.c_str(), &a6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&a6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&a6) && a6.s6_addr[12] == 127;
  }
  return false;
}

bool split_host(std::string_view header, std::string& name, int& port) {
  port = -1;
  std::string_view rest;
  if (!header.empty() && header.front() == '[') {
    const auto close = header.find(']');
    if (close == std::string_view::npos) return false;
    name = std::string(header.substr(1, close - 1));
    rest = header.substr(close + 1);
  } else {
    const auto colon = header.find(':');
    name = std::string(header.substr(0, colon));
    rest = colon == std::string_view::npos ? std::string_view() : header.substr(colon);
  }
  if (rest.empty()) return !name.empty();
  if (rest.front() != ':' || rest.size() < 2 || rest.size() > 6) return false;
  int p = 0;
  for (char c : rest.substr(1)) {
    if (c < '0' || c > '9') return false;
    p = p * 10 + (c - '0');
  }
  port = p;
  return !name.empty() && p <= 65535;
}

Access::Access(const Settings& s)
    : bound_host_(s.http_host), loopback_bind_(is_loopback(s.http_host)), tls_(!s.http_tls_cert.empty()) {
  if (!s.http_token_file.empty()) {
    token_digest_ = sha256(read_token(s.http_token_file));
    token_required_ = true;
  }
  session_ = new_session_secret();
  session_digest_ = sha256(session_);
}

std::string Access::reload_token(const std::filesystem::path& file) {
  if (!token_required_) throw std::runtime_error("http: no token_file at start, none to reload");
  const Digest next = sha256(read_token(file));
  // Made before the lock is taken, and before anything changes: it may fail.
  const std::string session = new_session_secret();
  std::lock_guard lock(mu_);
  if (same(next, token_digest_)) return "applied: the same token";
  token_digest_ = next;
  session_ = session;
  session_digest_ = sha256(session_);
  return "applied: a new token; viewer sessions opened with the old one have ended";
}

bool Access::token_matches(std::string_view presented) const {
  const Digest d = sha256(presented);
  std::lock_guard lock(mu_);
  return token_required_ && same(d, token_digest_);
}

bool Access::session_matches(std::string_view presented) const {
  if (presented.empty()) return false;
  const Digest d = sha256(presented);
  std::lock_guard lock(mu_);
  return same(d, session_digest_);
}

bool Access::host_allowed(std::string_view header) const {
  std::string name;
  int port = -1;
  if (!split_host(header, name, port)) return false;
  if (port >= 0 && port != port_) return false;
  for (auto& c : name) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c + 32 : c);
  return name == "127.0.0.1" || name == "localhost" || name == "::1" || name == bound_host_;
}

bool Access::admit(const httplib::Request& req, httplib::Response& res) const {
  // No Host at all (HTTP/1.0, a bare script) is no rebinding: every browser sends one.
  if (loopback_bind_ && req.has_header("Host") && !host_allowed(req.get_header_value("Host"))) {
    send_error(res, 403, "bad_host",
               "this server answers only to its own name (127.0.0.1, localhost, [::1] with port " +
                   std::to_string(port_) + ")");
    return false;
  }
  if (!token_required_ || req.path == "/healthz" || (req.method == "POST" && req.path == "/v1/session"))
    return true;
  std::string storage;
  if (const auto t = bearer(req, storage); !t.empty() && token_matches(t)) return true;
  if (session_matches(cookie(req.get_header_value("Cookie"), kCookieName))) return true;
  unauthorized(req, res);
  return false;
}

void Access::open_session(const httplib::Request& req, httplib::Response& res) const {
  if (!token_required_) {
    send_error(res, 404, "no_token", "this server takes no token: nothing to open");
    return;
  }
  std::string storage;
  std::string presented(bearer(req, storage));
  if (presented.empty()) presented = form_field(req.body, "token");
  if (!token_matches(presented)) {
    res.set_header("WWW-Authenticate", "Bearer realm=\"naneyed\"");
    send_error(res, 401, "unauthorized", "wrong or missing token");
    return;
  }
  std::string session;
  {
    std::lock_guard lock(mu_);
    session = session_;
  }
  // HttpOnly: no script (an injected one included) reads it; SameSite=Strict: no other site's page
  // makes the browser send it; no Max-Age: it ends with the browser session, and with this daemon's
  // run or its token (the value is random per start and per new token).
  res.set_header("Set-Cookie", std::string(kCookieName) + "=" + session +
                                   "; Path=/; HttpOnly; SameSite=Strict" + (tls_ ? "; Secure" : ""));
  res.set_header("Location", "/");
  res.set_header("Cache-Control", "no-store");
  res.status = 303;
  set_body(res, "", "text/plain");
}

}  // namespace naneye::daemon::http
