// Who may ask naneyed (issue 13, access): the bearer token and the viewer's session cookie, the Host
// check against DNS rebinding on loopback, no absolute paths for remote clients, the warning for a
// bind beyond loopback without a token. TLS is in test_http_tls.cpp.
#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include "naneyed_fixture.hpp"
#include "raw_client.hpp"

using namespace naneye::daemon::test;

namespace {

constexpr const char* kToken = "3f1c0e6b9a8d4c2e7f5a1b3c9d0e8f7a";

std::string get(const std::string& path, const std::string& headers) {
  return "GET " + path + " HTTP/1.1\r\n" + headers + "Connection: close\r\n\r\n";
}

std::string body_of(const std::string& response) {
  const auto at = response.find("\r\n\r\n");
  return at == std::string::npos ? std::string() : response.substr(at + 4);
}

// The value of header `name` (case as the daemon writes it), or empty.
std::string header_of(const std::string& response, const std::string& name) {
  const auto at = response.find("\r\n" + name + ": ");
  if (at == std::string::npos) return {};
  const auto from = at + name.size() + 4;
  return response.substr(from, response.find("\r\n", from) - from);
}

// An IPv4 address of this machine that is not loopback, or nothing.
std::optional<in_addr_t> non_loopback_address() {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return std::nullopt;
  std::optional<in_addr_t> found;
  for (ifaddrs* i = list; i && !found; i = i->ifa_next) {
    if (!i->ifa_addr || i->ifa_addr->sa_family != AF_INET) continue;
    const auto a = reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr.s_addr;
    if ((ntohl(a) >> 24) != 127) found = a;
  }
  freeifaddrs(list);
  return found;
}

}  // namespace

class NaneyedAccess : public NaneyedTest {
 protected:
  std::string token_config() {
    const auto file = dir.path / "token";
    std::ofstream(file) << kToken << "\n";  // the newline `echo` adds is not part of the token
    chmod(file.c_str(), 0640);
    return "token_file = \"" + file.string() + "\"\n";
  }
  std::string host() const { return "Host: 127.0.0.1:" + std::to_string(port) + "\r\n"; }
};

TEST_F(NaneyedAccess, WithATokenFileEveryRequestButHealthzMustPresentIt) {
  start(token_config() + looping_source(capture(12)));
  auto r = round_trip(port, get("/v1/status", host()));
  EXPECT_EQ(status_of(r), 401) << r;
  EXPECT_EQ(header_of(r, "WWW-Authenticate"), "Bearer realm=\"naneyed\"");
  EXPECT_EQ(nlohmann::json::parse(body_of(r))["error"], "unauthorized");
  r = round_trip(port, get("/v1/depth", host() + "Authorization: Bearer " + std::string(kToken) + "x\r\n"));
  EXPECT_EQ(status_of(r), 401) << "a longer token is not the token";
  r = round_trip(port,
                 get("/v1/status", host() + "Authorization: Bearer " + std::string(kToken, 31) + "\r\n"));
  EXPECT_EQ(status_of(r), 401) << "nor is a prefix";
  r = round_trip(port, get("/v1/status", host() + "Authorization: Bearer " + kToken + "\r\n"));
  EXPECT_EQ(status_of(r), 200) << r;
  r = round_trip(port, get("/v1/status", host() + "Authorization: bearer " + kToken + "\r\n"));
  EXPECT_EQ(status_of(r), 200) << "the scheme's name is case-insensitive";
  EXPECT_EQ(status_of(round_trip(port, get("/healthz", host()))), 200);
  EXPECT_EQ(status_of(round_trip(port, get("/metrics", host()))), 401);
}

TEST_F(NaneyedAccess, TheViewerTradesTheTokenOnceForAStrictHttpOnlyCookieThatItsStreamsCarry) {
  // EventSource and <img> cannot send an Authorization header: the viewer presents the token once
  // (a form on the 401 page) and the browser sends the cookie with every same-origin request.
  start(token_config() + looping_source(capture(12)));
  const auto page = round_trip(port, get("/", host()));
  EXPECT_EQ(status_of(page), 401);
  EXPECT_NE(header_of(page, "Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(body_of(page).find("action=\"/v1/session\""), std::string::npos) << page;
  EXPECT_NE(header_of(page, "Content-Security-Policy").find("form-action 'self'"), std::string::npos);

  const auto post = [&](const std::string& body) {
    return round_trip(port, "POST /v1/session HTTP/1.1\r\n" + host() +
                                "Content-Type: application/x-www-form-urlencoded\r\nContent-Length: " +
                                std::to_string(body.size()) + "\r\nConnection: close\r\n\r\n" + body);
  };
  EXPECT_EQ(status_of(post("token=wrong")), 401);
  EXPECT_TRUE(header_of(post("token=wrong"), "Set-Cookie").empty());
  const auto ok = post(std::string("token=") + kToken);
  ASSERT_EQ(status_of(ok), 303) << ok;
  EXPECT_EQ(header_of(ok, "Location"), "/");
  const std::string set_cookie = header_of(ok, "Set-Cookie");
  EXPECT_NE(set_cookie.find("; HttpOnly"), std::string::npos) << set_cookie;
  EXPECT_NE(set_cookie.find("; SameSite=Strict"), std::string::npos) << set_cookie;
  EXPECT_EQ(set_cookie.find(kToken), std::string::npos) << "the cookie is not the token";
  const std::string cookie = "Cookie: other=1; " + set_cookie.substr(0, set_cookie.find(';')) + "\r\n";

  EXPECT_EQ(status_of(round_trip(port, get("/", host() + cookie))), 200);
  EXPECT_EQ(status_of(round_trip(port, get("/web/viewer.js", host() + cookie))), 200);
  EXPECT_EQ(status_of(round_trip(port, get("/v1/status", host() + cookie))), 200);
  EXPECT_EQ(status_of(round_trip(port, get("/v1/status", host() + "Cookie: naneye_session=00\r\n"))), 401);
  // The event stream answers 200 and its first event (read until it arrives, then hang up).
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const std::string req = "GET /v1/events HTTP/1.1\r\n" + host() + cookie + "\r\n";
  ASSERT_EQ(send(fd, req.data(), req.size(), MSG_NOSIGNAL), static_cast<ssize_t>(req.size()));
  std::string in;
  char buf[4096];
  for (int k = 0; k < 100 && in.find("event: result") == std::string::npos; ++k) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 5000) <= 0) break;
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    in.append(buf, static_cast<std::size_t>(n));
  }
  close(fd);
  EXPECT_EQ(status_of(in), 200) << in.substr(0, 200);
  EXPECT_NE(in.find("event: result"), std::string::npos) << in.substr(0, 200);
}

TEST_F(NaneyedAccess, OnLoopbackARequestForAnotherHostNameIsRefused) {
  // DNS rebinding: a page from evil.example, its name re-pointed at 127.0.0.1, reads the daemon
  // through the visitor's browser; the browser still says "Host: evil.example".
  start(looping_source(capture(12)));
  const std::string p = std::to_string(port);
  const std::vector<std::string> refused{"evil.example", "evil.example:" + p,
                                         "127.0.0.1:1",  "127.0.0.1.evil.example:" + p,
                                         "[::1]:1",      "localhost:" + p + "x"};
  for (const auto& h : refused) {
    const auto r = round_trip(port, get("/v1/status", "Host: " + h + "\r\n"));
    EXPECT_EQ(status_of(r), 403) << h << "\n" << r;
    if (status_of(r) == 403) {
      EXPECT_EQ(nlohmann::json::parse(body_of(r))["error"], "bad_host") << h;
    }
  }
  const std::vector<std::string> served{"127.0.0.1:" + p, "127.0.0.1", "localhost:" + p, "LocalHost:" + p,
                                        "[::1]:" + p};
  for (const auto& h : served) {
    EXPECT_EQ(status_of(round_trip(port, get("/v1/status", "Host: " + h + "\r\n"))), 200) << h;
  }
  // No Host at all (HTTP/1.0, a bare script) is no browser, so no rebinding.
  EXPECT_EQ(status_of(round_trip(port, "GET /healthz HTTP/1.0\r\n\r\n")), 200);
}

TEST_F(NaneyedAccess, BeyondLoopbackStatusNamesFilesWithoutTheirFoldersAndNoTokenIsWarnedAbout) {
  const auto remote = non_loopback_address();
  if (!remote) GTEST_SKIP() << "this machine has no IPv4 address besides loopback";
  const auto file = capture(12);
  start(looping_source(file), {"--listen", "0.0.0.0:0"});
  EXPECT_NE(daemon->log().find("beyond loopback WITHOUT A TOKEN"), std::string::npos) << daemon->log();
  const auto local = get_json("/v1/status");
  EXPECT_NE(local.dump().find(file.parent_path().string() + "/"), std::string::npos)
      << "loopback sees it all";
  const auto r = round_trip(port, get("/v1/status", ""), *remote);
  ASSERT_EQ(status_of(r), 200) << r;
  const auto j = nlohmann::json::parse(body_of(r));
  const std::string text = j.dump();
  EXPECT_EQ(text.find(file.parent_path().string()), std::string::npos) << text;
  EXPECT_EQ(text.find(std::string(NANEYE_SOURCE_DIR)), std::string::npos) << text;
  EXPECT_EQ(j["calibration"]["files"], nlohmann::json({"paper-d3.yaml"}));
  EXPECT_EQ(j["source"]["uri"], "file://capture.raw?speed=realtime&loop=1");
  EXPECT_EQ(j["source"]["requested"], "file://capture.raw?speed=realtime&loop=1");
  // Beyond loopback there is no Host check: the daemon may have any number of names.
  EXPECT_EQ(status_of(round_trip(port, get("/healthz", "Host: naneye.lab.example\r\n"), *remote)), 200);
}

TEST_F(NaneyedAccess, ATokenFileThatIsMissingOrTooShortIsRefusedAtStart) {
  const auto file = dir.path / "short";
  std::ofstream(file) << "abc\n";
  const auto cfg = dir.path / "bad.toml";
  std::ofstream(cfg) << "[calibration]\npath = \"" << calib_path() << "\"\n[http]\nport = 0\ntoken_file = \""
                     << file.string() << "\"\n"
                     << looping_source(capture(4));
  DaemonProcess d({"--config", cfg.string()}, dir.path / "short.log");
  EXPECT_EQ(d.wait_exit(), 1);
  EXPECT_NE(d.log().find("at least 16 characters"), std::string::npos) << d.log();
  std::ofstream(cfg) << "[calibration]\npath = \"" << calib_path()
                     << "\"\n[http]\nport = 0\ntoken_file = \"/nonexistent/token\"\n";
  DaemonProcess e({"--config", cfg.string(), "--check-config"}, dir.path / "missing.log");
  EXPECT_EQ(e.wait_exit(), 1);
  EXPECT_NE((e.log() + e.out()).find("http.token_file: no such file"), std::string::npos)
      << e.log() << e.out();
}

TEST_F(NaneyedAccess, OnSighupTheTokenFileIsReadAgainAndABadOneKeepsTheTokenInUse) {
  // A token is rotated because it may have leaked: after SIGHUP the old one and the sessions it
  // bought are refused, the new one works; a file that cannot be used leaves the token as it was.
  constexpr const char* kNewToken = "9b2d7e4f1a6c8e0d3b5f7a9c1e3d5b7f";
  start(token_config() + looping_source(capture(12)));
  const auto with = [&](const std::string& token, const std::string& path = "/v1/status") {
    return round_trip(port, get(path, host() + "Authorization: Bearer " + token + "\r\n"));
  };
  const auto status_with = [&](const std::string& token) {
    return nlohmann::json::parse(body_of(with(token)));
  };
  const std::string login = std::string("token=") + kToken;
  const auto ok =
      round_trip(port, "POST /v1/session HTTP/1.1\r\n" + host() +
                           "Content-Type: application/x-www-form-urlencoded\r\nContent-Length: " +
                           std::to_string(login.size()) + "\r\nConnection: close\r\n\r\n" + login);
  const std::string set_cookie = header_of(ok, "Set-Cookie");
  const std::string cookie = "Cookie: " + set_cookie.substr(0, set_cookie.find(';')) + "\r\n";
  ASSERT_EQ(status_of(round_trip(port, get("/v1/status", host() + cookie))), 200);
  EXPECT_TRUE(status_with(kToken)["http"]["token"]["last_reload"].is_null());

  const auto file = dir.path / "token";
  std::ofstream(file, std::ios::trunc) << kNewToken << "\n";
  daemon->signal(SIGHUP);
  // The reload happens on the daemon's main thread: wait (bounded) until the new token is taken.
  for (int k = 0; k < 300 && status_of(with(kNewToken)) != 200; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(status_of(with(kNewToken)), 200) << daemon->log();
  EXPECT_EQ(status_of(with(kToken)), 401) << "the old token still opens the daemon";
  EXPECT_EQ(status_of(round_trip(port, get("/v1/status", host() + cookie))), 401)
      << "a session bought with the old token outlived it";
  auto s = status_with(kNewToken)["http"]["token"];
  EXPECT_EQ(s["reloads"], 1);
  EXPECT_EQ(s["last_reload"]["ok"], true);
  EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find("a new token"), std::string::npos) << s;

  struct Case {
    std::string text, reason;
  };
  int failures = 0;
  for (const Case& c : {Case{"short\n", "at least 16 characters"}, Case{"", "at least 16"},
                        Case{"two tokens 9b2d7e4f1a6c8e0d3b5f\n", "without spaces"}}) {
    std::ofstream(file, std::ios::trunc) << c.text;
    daemon->signal(SIGHUP);
    ++failures;
    for (int k = 0; k < 300 && status_with(kNewToken)["http"]["token"]["reload_failures"] != failures; ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    s = status_with(kNewToken)["http"]["token"];
    EXPECT_EQ(s["reload_failures"], failures) << daemon->log();
    EXPECT_EQ(s["last_reload"]["ok"], false);
    EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find(c.reason), std::string::npos) << s;
    EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find(file.string()), std::string::npos)
        << "a loopback client is shown the file's path";
    EXPECT_EQ(status_of(with(kNewToken)), 200) << "a refused file changed the token in use";
    EXPECT_EQ(status_of(with(kToken)), 401);
  }
  // Rotated by a rename that has not happened yet: no file at all.
  std::filesystem::remove(file);
  daemon->signal(SIGHUP);
  for (int k = 0; k < 300 && status_with(kNewToken)["http"]["token"]["reload_failures"] != 4; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  s = status_with(kNewToken)["http"]["token"];
  EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find("cannot be read"), std::string::npos) << s;
  EXPECT_EQ(status_of(with(kNewToken)), 200);
  const auto m = body_of(with(kNewToken, "/metrics"));
  EXPECT_NE(m.find("\nnaneye_http_token_reloads_total 1\n"), std::string::npos) << m;
  EXPECT_NE(m.find("\nnaneye_http_token_reload_failures_total 4\n"), std::string::npos);
  EXPECT_NE(m.find("\nnaneye_http_token_last_reload_ok 0\n"), std::string::npos);
  EXPECT_NE(m.find("\nnaneye_http_tls_last_reload_ok -1\n"), std::string::npos) << "no TLS: no reload";
  EXPECT_NE(daemon->log().find("token not reloaded, keeping the current one"), std::string::npos);
  EXPECT_EQ(daemon->stop(SIGTERM).first, 0) << daemon->log();
}
