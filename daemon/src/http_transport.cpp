#include "http_transport.hpp"

#include <fcntl.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>
#include <poll.h>
#include <sys/socket.h>

#include <cerrno>
#include <stdexcept>

namespace naneye::daemon::http {
namespace {

std::string openssl_reason() {
  const unsigned long e = ERR_get_error();
  char text[256] = "unknown error";
  if (e != 0) ERR_error_string_n(e, text, sizeof text);
  ERR_clear_error();
  return text;
}

}  // namespace

TlsContext::TlsContext(const std::string& cert_file, const std::string& key_file) {
  ctx_ = SSL_CTX_new(TLS_server_method());
  if (!ctx_) throw std::runtime_error("tls: cannot create a context: " + openssl_reason());
  // TLS 1.2 and 1.3 only (RFC 8996 deprecates 1.0 and 1.1). No session tickets: each would be one
  // more write after the handshake, and a client reconnecting a few times an hour gains nothing.
  // A client that closes without close_notify reads as an end of stream, as a plain close does.
  SSL_CTX_set_min_proto_version(ctx_, TLS1_2_VERSION);
  SSL_CTX_set_num_tickets(ctx_, 0);
  SSL_CTX_set_options(ctx_, SSL_OP_IGNORE_UNEXPECTED_EOF | SSL_OP_NO_RENEGOTIATION);
  // Writes may complete partly, as send() does: RequestStream keeps what is left.
  SSL_CTX_set_mode(ctx_, SSL_MODE_ENABLE_PARTIAL_WRITE | SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  if (SSL_CTX_use_certificate_chain_file(ctx_, cert_file.c_str()) != 1) {
    const auto why = openssl_reason();
    SSL_CTX_free(ctx_);
    throw std::runtime_error("http.tls_cert " + cert_file + ": " + why);
  }
  if (SSL_CTX_use_PrivateKey_file(ctx_, key_file.c_str(), SSL_FILETYPE_PEM) != 1 ||
      SSL_CTX_check_private_key(ctx_) != 1) {
    const auto why = openssl_reason();
    SSL_CTX_free(ctx_);
    throw std::runtime_error("http.tls_key " + key_file + ": " + why);
  }
}

TlsContext::~TlsContext() {
  SSL_CTX_free(ctx_);
}

std::string TlsContext::describe() const {
  X509* cert = SSL_CTX_get0_certificate(ctx_);
  if (!cert) return "no certificate";
  std::string out;
  if (BIO* bio = BIO_new(BIO_s_mem())) {
    X509_NAME_print_ex(bio, X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
    BIO_puts(bio, ", valid until ");
    ASN1_TIME_print(bio, X509_get0_notAfter(cert));
    char* text = nullptr;
    const long n = BIO_get_mem_data(bio, &text);
    if (n > 0) out.assign(text, static_cast<std::size_t>(n));
    BIO_free(bio);
  }
  ERR_clear_error();
  return out;
}

Transport::Transport(int fd, std::shared_ptr<const TlsContext> tls) : fd_(fd), tls_(std::move(tls)) {
  if (!tls_) return;
  // OpenSSL reads and writes the socket itself: non-blocking, so that every step returns at once.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  ssl_ = SSL_new(tls_->get());
  if (ssl_) SSL_set_fd(ssl_, fd);
  established_ = false;
}

Transport::~Transport() {
  if (ssl_) SSL_free(ssl_);
}

Io Transport::ssl_result(int ret) {
  switch (SSL_get_error(ssl_, ret)) {
    case SSL_ERROR_WANT_READ:
      return Io::want_read;
    case SSL_ERROR_WANT_WRITE:
      return Io::want_write;
    case SSL_ERROR_ZERO_RETURN:
      return Io::closed;
    default:
      // The queue holds this connection's reason only; it must not be left for another's call.
      ERR_clear_error();
      failed_ = true;
      return Io::failed;
  }
}

Io Transport::handshake() {
  if (established_) return Io::done;
  if (!ssl_) return Io::failed;
  const int r = SSL_accept(ssl_);
  if (r == 1) {
    established_ = true;
    return Io::done;
  }
  return ssl_result(r);
}

Io Transport::read(char* buf, std::size_t size, std::size_t& got) {
  got = 0;
  if (!ssl_) {
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, size, MSG_DONTWAIT);
      if (n > 0) {
        got = static_cast<std::size_t>(n);
        return Io::done;
      }
      if (n == 0) return Io::closed;
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK ? Io::want_read : Io::failed;
    }
  }
  const int r = SSL_read_ex(ssl_, buf, size, &got);
  return r == 1 ? Io::done : ssl_result(r);
}

Io Transport::write(const char* buf, std::size_t size, std::size_t& put) {
  put = 0;
  if (!ssl_) {
    for (;;) {
      const ssize_t n = ::send(fd_, buf, size, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n >= 0) {
        put = static_cast<std::size_t>(n);
        return Io::done;
      }
      if (errno == EINTR) continue;
      return errno == EAGAIN || errno == EWOULDBLOCK ? Io::want_write : Io::failed;
    }
  }
  // OpenSSL's socket BIO writes with write(2): a client gone away raises SIGPIPE, which naneyed
  // ignores (naneyed_main.cpp), so the write fails with EPIPE instead.
  const int r = SSL_write_ex(ssl_, buf, size, &put);
  return r == 1 ? Io::done : ssl_result(r);
}

bool Transport::write_all(const char* buf, std::size_t size, std::chrono::milliseconds timeout) {
  using Clock = std::chrono::steady_clock;
  const auto until = Clock::now() + timeout;
  std::size_t done = 0;
  while (done < size) {
    std::size_t put = 0;
    const Io r = write(buf + done, size - done, put);
    if (r == Io::done) {
      done += put;
      continue;
    }
    if (r != Io::want_read && r != Io::want_write) return false;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now());
    if (left.count() <= 0) return false;
    pollfd p{fd_, static_cast<short>(r == Io::want_read ? POLLIN : POLLOUT), 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0 || (p.revents & (POLLERR | POLLHUP))) return false;
  }
  return true;
}

void Transport::close_notify() {
  if (!ssl_ || !established_ || failed_) return;
  SSL_shutdown(ssl_);
  ERR_clear_error();
}

}  // namespace naneye::daemon::http
