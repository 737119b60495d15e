// GET / and /web/<file>: the live viewer (daemon/web/), served from the binary. The page reads only
// the public API, like any other client, so serving it adds nothing to the pipeline's path.
#include <string>

#include "http_internal.hpp"
#include "web_assets.hpp"

namespace naneye::daemon::http {
namespace {

const char* content_type(std::string_view name) {
  const auto ends = [&](std::string_view ext) {
    return name.size() >= ext.size() && name.substr(name.size() - ext.size()) == ext;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  return "application/octet-stream";
}

const web::Asset* find_asset(std::string_view name) {
  for (const auto& a : web::assets())
    if (a.name == name) return &a;
  return nullptr;
}

void serve(httplib::Response& res, const web::Asset& a) {
  // Same origin only: the page works with no network and cannot be made to talk to anything else.
  res.set_header("Content-Security-Policy",
                 "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
                 "frame-ancestors 'none'; base-uri 'none'; form-action 'none'");
  res.set_header("X-Content-Type-Options", "nosniff");
  // Small files that change with the binary: revalidated on every load, never stale after an upgrade.
  res.set_header("Cache-Control", "no-cache");
  set_body(res, std::string(a.data), content_type(a.name));
}

}  // namespace

void serve_login(httplib::Response& res) {
  const auto* a = find_asset("login.html");
  if (!a) return send_error(res, 401, "unauthorized", "this server needs its token");
  // As the viewer's policy, but its one form may post (to this origin only).
  res.set_header("Content-Security-Policy",
                 "default-src 'none'; form-action 'self'; frame-ancestors 'none'; base-uri 'none'");
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Cache-Control", "no-store");
  set_body(res, std::string(a->data), content_type(a->name));
}

void add_web_routes(httplib::Server& svr) {
  svr.Get("/", [](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    if (const auto* a = find_asset("index.html")) return serve(res, *a);
    send_error(res, 500, "no_viewer", "this build has no viewer assets");
  });
  svr.Get(R"(/web/([a-z0-9_.-]+))", [](const httplib::Request& req, httplib::Response& res) {
    if (!only_params(req, res, {})) return;
    if (const auto* a = find_asset(req.matches[1].str())) return serve(res, *a);
    send_error(res, 404, "not_found", "no viewer file " + req.matches[1].str());
  });
}

}  // namespace naneye::daemon::http
