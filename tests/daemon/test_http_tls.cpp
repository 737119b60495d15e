// naneyed over HTTPS (http.tls_cert, http.tls_key): a certificate made at test time with OpenSSL,
// requests and an event stream through httplib's SSLClient, and the gate's protections kept: a
// client that stalls its handshake is closed at the head deadline and holds no thread meanwhile.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cstdio>
#include <functional>

#include "naneyed_fixture.hpp"

using namespace naneye::daemon::test;

namespace {

// A self-signed P-256 certificate for "localhost", valid for an hour, written as PEM; `serial`
// tells one certificate from another.
bool write_self_signed(const std::filesystem::path& cert, const std::filesystem::path& key, long serial = 1) {
  EVP_PKEY* pkey = EVP_EC_gen("P-256");
  X509* x = X509_new();
  bool ok = pkey && x;
  if (ok) {
    X509_set_version(x, 2);
    ASN1_INTEGER_set(X509_get_serialNumber(x), serial);
    X509_gmtime_adj(X509_getm_notBefore(x), 0);
    X509_gmtime_adj(X509_getm_notAfter(x), 3600);
    X509_set_pubkey(x, pkey);
    X509_NAME* name = X509_get_subject_name(x);
    X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC, reinterpret_cast<const unsigned char*>("localhost"),
                               -1, -1, 0);
    X509_set_issuer_name(x, name);
    ok = X509_sign(x, pkey, EVP_sha256()) > 0;
  }
  if (ok) {
    FILE* k = std::fopen(key.c_str(), "w");
    FILE* c = std::fopen(cert.c_str(), "w");
    ok = k && c && PEM_write_PrivateKey(k, pkey, nullptr, nullptr, 0, nullptr, nullptr) == 1 &&
         PEM_write_X509(c, x) == 1;
    if (k) std::fclose(k);
    if (c) std::fclose(c);
  }
  X509_free(x);
  EVP_PKEY_free(pkey);
  return ok;
}

int connect_to(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// The serial number of the certificate the server presents in a fresh handshake, -1 if none
// (reads bounded by a 5 s socket timeout: a server that stalls fails the test, not hangs it).
long served_serial(int port) {
  const int fd = connect_to(port);
  if (fd < 0) return -1;
  timeval five{5, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &five, sizeof five);
  SSL_CTX* ctx = SSL_CTX_new(TLS_client_method());
  SSL* ssl = ctx ? SSL_new(ctx) : nullptr;
  long serial = -1;
  if (ssl && SSL_set_fd(ssl, fd) == 1 && SSL_connect(ssl) == 1) {
    if (X509* c = SSL_get1_peer_certificate(ssl)) {
      serial = ASN1_INTEGER_get(X509_get0_serialNumber(c));
      X509_free(c);
    }
    SSL_shutdown(ssl);
  }
  SSL_free(ssl);
  SSL_CTX_free(ctx);
  close(fd);
  return serial;
}

// Seconds until the server closes `fd` (reads return 0 or fail), or -1 after `limit_s`.
double seconds_until_closed(int fd, double limit_s) {
  const auto t0 = std::chrono::steady_clock::now();
  char buf[512];
  for (;;) {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (t > limit_s) return -1;
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 100) > 0 && recv(fd, buf, sizeof buf, 0) <= 0) return t;
  }
}

}  // namespace

class NaneyedTls : public NaneyedTest {
 protected:
  std::unique_ptr<httplib::SSLClient> tls;

  void start_tls(const std::string& extra) {
    const auto cert = dir.path / "cert.pem", key = dir.path / "key.pem";
    ASSERT_TRUE(write_self_signed(cert, key));
    start("tls_cert = \"" + cert.string() + "\"\ntls_key = \"" + key.string() + "\"\n" + extra +
          "[source]\nuri = \"file://" + capture(12).string() + "?speed=realtime&loop=1\"\n");
    tls = std::make_unique<httplib::SSLClient>("127.0.0.1", port);
    tls->enable_server_certificate_verification(false);  // self-signed, made above
    tls->set_read_timeout(5, 0);
    tls->set_connection_timeout(5, 0);
  }
};

TEST_F(NaneyedTls, RequestsAndEventsAreServedOverTlsAndPlainHttpIsNot) {
  start_tls("");
  EXPECT_NE(daemon->log().find("listening on https://127.0.0.1:"), std::string::npos) << daemon->log();
  const auto r = tls->Get("/v1/status");
  ASSERT_TRUE(r) << httplib::to_string(r.error());
  EXPECT_EQ(r->status, 200);
  const auto j = nlohmann::json::parse(r->body);
  EXPECT_EQ(j["http"]["tls_failures"], 0);
  // Keep-alive over one session: the connection goes back to the gate between requests.
  for (int k = 0; k < 5; ++k) {
    const auto again = tls->Get("/healthz");
    ASSERT_TRUE(again) << k;
    EXPECT_EQ(again->status, 200);
  }
  // The event stream: its first event arrives through the session.
  std::string events;
  const auto ev = tls->Get("/v1/events", [&](const char* data, std::size_t n) {
    events.append(data, n);
    return events.find("event: result") == std::string::npos;  // hang up after the first event
  });
  EXPECT_NE(events.find("event: result"), std::string::npos) << events.substr(0, 200);
  // A plain-HTTP request on the TLS port is no handshake: closed, counted, never answered in clear.
  const int fd = connect_to(port);
  ASSERT_GE(fd, 0);
  const std::string plain = "GET /v1/status HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  ASSERT_EQ(send(fd, plain.data(), plain.size(), MSG_NOSIGNAL), static_cast<ssize_t>(plain.size()));
  char buf[256];
  pollfd p{fd, POLLIN, 0};
  const ssize_t n = poll(&p, 1, 5000) > 0 ? recv(fd, buf, sizeof buf, 0) : -2;
  EXPECT_TRUE(n <= 0 || std::string(buf, static_cast<std::size_t>(n)).find("HTTP/1.1") != 0)
      << "answered in clear text";
  close(fd);
  const auto after = tls->Get("/v1/status");
  ASSERT_TRUE(after);
  EXPECT_EQ(nlohmann::json::parse(after->body)["http"]["tls_failures"], 1);
}

TEST_F(NaneyedTls, AStalledHandshakeIsASlowClientClosedAtItsDeadlineWhileOthersAreServed) {
  // 20 clients that connect and send half a ClientHello (or nothing): with a blocking SSL_accept
  // on a pool thread, 8 of them would stop all service, as slowloris did before the gate.
  // 2 s: the deadline also covers the 20 connections and the test's own handshake, which a sanitizer
  // build on a loaded machine must complete within it.
  start_tls("head_timeout_ms = 2000\n");
  std::vector<int> stalled;
  const unsigned char half_hello[] = {0x16, 0x03, 0x01, 0x02, 0x00, 0x01, 0x00, 0x01, 0xfc};
  for (int i = 0; i < 20; ++i) {
    const int fd = connect_to(port);
    ASSERT_GE(fd, 0);
    if (i % 2 == 0) send(fd, half_hello, sizeof half_hello, MSG_NOSIGNAL);
    stalled.push_back(fd);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = tls->Get("/v1/status");
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(r) << "no answer with 20 stalled handshakes";
  EXPECT_EQ(r->status, 200);
  EXPECT_GE(nlohmann::json::parse(r->body)["http"]["connections"].get<int>(), 20);
  std::printf("[ figures ] /v1/status over TLS with 20 stalled handshakes: %.1f ms\n", ms);
  // Each is closed at its deadline (2 s from its accept), not left open.
  for (int fd : stalled) {
    const double s = seconds_until_closed(fd, 5.0);
    EXPECT_GE(s, 0.0) << "a stalled handshake was still open after 5 s";
    close(fd);
  }
}

TEST_F(NaneyedTls, ACertificateThatDoesNotLoadIsRefusedByCheckConfig) {
  const auto cert = dir.path / "cert.pem", key = dir.path / "key.pem";
  ASSERT_TRUE(write_self_signed(cert, key));
  const auto garbage = dir.path / "garbage.pem";
  std::ofstream(garbage) << "-----BEGIN CERTIFICATE-----\nnot base64\n-----END CERTIFICATE-----\n";
  const auto cfg = dir.path / "tls.toml";
  const auto write = [&](const std::filesystem::path& c, const std::filesystem::path& k) {
    std::ofstream(cfg) << "[calibration]\npath = \"" << calib_path() << "\"\n[http]\ntls_cert = \""
                       << c.string() << "\"\ntls_key = \"" << k.string() << "\"\n[source]\nuri = \"file://"
                       << capture(4).string() << "\"\n";
  };
  write(cert, key);
  DaemonProcess good({"--config", cfg.string(), "--check-config"}, dir.path / "good.log");
  EXPECT_EQ(good.wait_exit(), 0) << good.log();
  write(garbage, key);
  DaemonProcess bad({"--config", cfg.string(), "--check-config"}, dir.path / "bad.log");
  EXPECT_EQ(bad.wait_exit(), 1);
  EXPECT_NE(bad.log().find("http.tls_cert " + garbage.string()), std::string::npos) << bad.log();
}

TEST_F(NaneyedTls, OnSighupANewCertificateIsServedAndOneThatDoesNotLoadKeepsTheOld) {
  start_tls("");
  const auto cert = dir.path / "cert.pem", key = dir.path / "key.pem";
  ASSERT_EQ(served_serial(port), 1);
  const auto tls_status = [&] {
    const auto r = tls->Get("/v1/status");
    return r ? nlohmann::json::parse(r->body)["http"]["tls"] : nlohmann::json();
  };
  EXPECT_TRUE(tls_status()["last_reload"].is_null());

  // A renewed certificate (and its new key): the handshakes that follow present it.
  ASSERT_TRUE(write_self_signed(cert, key, 2));
  daemon->signal(SIGHUP);
  for (int k = 0; k < 300 && served_serial(port) != 2; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(served_serial(port), 2) << daemon->log();
  auto s = tls_status();
  EXPECT_EQ(s["reloads"], 1);
  EXPECT_EQ(s["last_reload"]["ok"], true);
  EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find("CN=localhost, valid until"),
            std::string::npos)
      << s;

  // Each way a rotation goes wrong: a certificate that does not parse; a new certificate whose key
  // is not there yet (the old key does not match it); no certificate file at all.
  const auto other_key = dir.path / "other-key.pem", other_cert = dir.path / "other-cert.pem";
  ASSERT_TRUE(write_self_signed(other_cert, other_key, 3));
  struct Case {
    std::function<void()> damage;
    std::string reason;
  };
  const std::vector<Case> cases{
      {[&] {
         std::ofstream(cert, std::ios::trunc)
             << "-----BEGIN CERTIFICATE-----\nnot base64\n-----END CERTIFICATE-----\n";
       },
       "http.tls_cert " + cert.string()},
      {[&] {
         std::filesystem::copy_file(other_cert, cert, std::filesystem::copy_options::overwrite_existing);
       },
       "http.tls_key " + key.string()},
      {[&] { std::filesystem::remove(cert); }, "http.tls_cert " + cert.string()},
  };
  int failures = 0;
  for (const auto& c : cases) {
    c.damage();
    daemon->signal(SIGHUP);
    ++failures;
    for (int k = 0; k < 300 && tls_status()["reload_failures"] != failures; ++k)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    s = tls_status();
    EXPECT_EQ(s["reload_failures"], failures) << daemon->log();
    EXPECT_EQ(s["last_reload"]["ok"], false);
    EXPECT_NE(s["last_reload"]["reason"].get<std::string>().find(c.reason), std::string::npos) << s;
    EXPECT_EQ(served_serial(port), 2) << "a refused certificate replaced the one in use";
  }
  const auto m = tls->Get("/metrics");
  ASSERT_TRUE(m);
  EXPECT_NE(m->body.find("\nnaneye_http_tls_reloads_total 1\n"), std::string::npos) << m->body;
  EXPECT_NE(m->body.find("\nnaneye_http_tls_reload_failures_total 3\n"), std::string::npos);
  EXPECT_NE(m->body.find("\nnaneye_http_tls_last_reload_ok 0\n"), std::string::npos);
  EXPECT_NE(daemon->log().find("TLS certificate not reloaded, keeping the current one"), std::string::npos);
  EXPECT_EQ(daemon->stop(SIGTERM).first, 0) << daemon->log();
}
