#pragma once
// httplib's Server with each accepted connection handed to the gate (http_gate.hpp) instead of a
// pool thread: the gate reads and bounds requests, httplib parses, routes and writes them.
#include <memory>

#include "http_gate.hpp"
#include "http_internal.hpp"

namespace naneye::daemon::http {

// `gate` is set to the server's gate (owned by the server; start() it before listening). `tls` null:
// plain HTTP.
std::unique_ptr<httplib::Server> make_gated_server(const GateLimits& limits, HttpCounters& counters,
                                                   std::shared_ptr<const TlsContext> tls, Gate*& gate);

}  // namespace naneye::daemon::http
