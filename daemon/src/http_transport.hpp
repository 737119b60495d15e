#pragma once
// The bytes of one client connection: the plain socket, or a TLS session over it (http.tls_cert and
// http.tls_key). Everything here is non-blocking: the gate's poll thread drives each TLS handshake
// and each read step by step, as it reads plain request heads, so a client that stalls its
// handshake is one more slow client (head deadline, eviction, connection cap), never a held thread.
#include <chrono>
#include <cstddef>
#include <memory>
#include <string>

struct ssl_st;
struct ssl_ctx_st;

namespace naneye::daemon::http {

// What one non-blocking step did, or what it waits for.
enum class Io { done, want_read, want_write, closed, failed };

// The server's certificate and key, loaded at start and again on SIGHUP (a new context for the
// connections that follow; those open keep theirs).
class TlsContext {
 public:
  // PEM files; throws std::runtime_error naming the file and OpenSSL's reason.
  TlsContext(const std::string& cert_file, const std::string& key_file);
  ~TlsContext();
  TlsContext(const TlsContext&) = delete;
  TlsContext& operator=(const TlsContext&) = delete;
  ssl_ctx_st* get() const { return ctx_; }
  // The certificate's subject and end of validity ("CN=localhost, valid until Dec  2 14:00:00 2026
  // GMT"): what a reload says it applied.
  std::string describe() const;

 private:
  ssl_ctx_st* ctx_ = nullptr;
};

class Transport {
 public:
  // `tls` null: plain. The transport does not own `fd` (the gate closes it); it keeps `tls` for
  // as long as its session lives, whatever context later connections get.
  Transport(int fd, std::shared_ptr<const TlsContext> tls);
  ~Transport();
  Transport(const Transport&) = delete;
  Transport& operator=(const Transport&) = delete;

  int fd() const { return fd_; }
  bool tls() const { return ssl_ != nullptr; }
  // True once bytes can be read and written (at once for a plain socket).
  bool established() const { return established_; }
  // One step of the TLS handshake; done when established.
  Io handshake();
  // At most `size` bytes of request; done with `got` > 0, or what it waits for.
  Io read(char* buf, std::size_t size, std::size_t& got);
  // Some of `buf`; done with `put` > 0, or what it waits for.
  Io write(const char* buf, std::size_t size, std::size_t& put);
  // All of `buf` within `timeout`, polling as the session asks; false on an error or the timeout
  // (a client that does not read is not waited for).
  bool write_all(const char* buf, std::size_t size, std::chrono::milliseconds timeout);
  // Tells a TLS client the session ends (one non-blocking close_notify); nothing for plain.
  void close_notify();

 private:
  Io ssl_result(int ret);

  int fd_;
  std::shared_ptr<const TlsContext> tls_;
  ssl_st* ssl_ = nullptr;
  bool established_ = true;
  bool failed_ = false;  // a fatal TLS error: no close_notify may follow (SSL_shutdown(3))
};

}  // namespace naneye::daemon::http
