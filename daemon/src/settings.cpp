#include "naneye/daemon/settings.hpp"
#include "naneye/base/enum_table.hpp"

#include <spdlog/common.h>

#include <toml++/toml.h>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

namespace naneye::daemon {
namespace {

std::string type_name(const toml::node& n) {
  std::ostringstream os;
  os << n.type();
  return os.str();
}

[[noreturn]] void fail(const std::string& key, const std::string& what) {
  throw SettingsError(key + ": " + what);
}

std::string get_string(const toml::node& n, const std::string& key) {
  if (auto v = n.value<std::string>(); v && n.is_string()) return *v;
  fail(key, "expected a string, got " + type_name(n));
}

std::int64_t get_int(const toml::node& n, const std::string& key, std::int64_t lo, std::int64_t hi) {
  if (!n.is_integer()) fail(key, "expected an integer, got " + type_name(n));
  const auto v = *n.value<std::int64_t>();
  if (v < lo || v > hi) {
    fail(key, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + std::to_string(v));
  }
  return v;
}

double get_double(const toml::node& n, const std::string& key, double lo, double hi) {
  if (!n.is_number()) fail(key, "expected a number, got " + type_name(n));
  const auto v = *n.value<double>();
  if (!(v >= lo && v <= hi)) {
    std::ostringstream os;
    os << "must be in " << lo << ".." << hi << ", got " << v;
    fail(key, os.str());
  }
  return v;
}

bool get_bool(const toml::node& n, const std::string& key) {
  if (!n.is_boolean()) fail(key, "expected true or false, got " + type_name(n));
  return *n.value<bool>();
}

std::filesystem::path resolve(const std::filesystem::path& base, const std::string& p) {
  std::filesystem::path path(p);
  return path.is_relative() && !base.empty() ? (base / path).lexically_normal() : path;
}

using Setter = std::function<void(const toml::node&, const std::string& key)>;

// Every accepted key and how it lands in Settings; anything else is refused by name.
std::map<std::string, Setter> setters(Settings& s, const std::filesystem::path& base) {
  recon::StereoReconstructorSettings* r = &s.processor.reconstructor;  // captured by value below
  auto integer = [](int& field, std::int64_t lo, std::int64_t hi) {
    return [&field, lo, hi](const toml::node& n, const std::string& key) {
      field = static_cast<int>(get_int(n, key, lo, hi));
    };
  };
  return {
      {"source.uri", [&s](const toml::node& n, const std::string& k) { s.source_uri = get_string(n, k); }},
      {"source.sample_capture",
       [&s, base](const toml::node& n, const std::string& k) {
         s.sample_capture = resolve(base, get_string(n, k));
       }},
      {"calibration.path",
       [&s, base](const toml::node& n, const std::string& k) {
         s.calibration.clear();
         if (auto* arr = n.as_array()) {
           if (arr->empty()) fail(k, "expected at least one file");
           for (std::size_t i = 0; i < arr->size(); ++i) {
             s.calibration.push_back(
                 resolve(base, get_string(*arr->get(i), k + "[" + std::to_string(i) + "]")));
           }
         } else {
           s.calibration.push_back(resolve(base, get_string(n, k)));
         }
       }},
      {"http.host", [&s](const toml::node& n, const std::string& k) { s.http_host = get_string(n, k); }},
      {"http.port", integer(s.http_port, 0, 65535)},
      {"http.threads", integer(s.http_threads, 2, 256)},
      {"http.max_connections", integer(s.http_max_connections, 1, 65536)},
      {"http.head_timeout_ms", integer(s.http_head_timeout_ms, 50, 60'000)},
      {"http.idle_timeout_ms", integer(s.http_idle_timeout_ms, 50, 3'600'000)},
      {"http.token_file",
       [&s, base](const toml::node& n, const std::string& k) {
         s.http_token_file = resolve(base, get_string(n, k));
       }},
      {"http.tls_cert",
       [&s, base](const toml::node& n, const std::string& k) {
         s.http_tls_cert = resolve(base, get_string(n, k));
       }},
      {"http.tls_key",
       [&s, base](const toml::node& n, const std::string& k) {
         s.http_tls_key = resolve(base, get_string(n, k));
       }},
      {"pipeline.corner_sigma_px",
       [r](const toml::node& n, const std::string& k) {
         r->reconstruction.corner_sigma_px = get_double(n, k, 1e-4, 10.0);
       }},
      {"pipeline.max_result_age_ms", integer(s.max_result_age_ms, 1, 3'600'000)},
      // The board's grid is the detector's, its square size the reconstruction's (recon's structs).
      {"board.rows", integer(r->corners.board.rows, 2, 8)},
      {"board.cols", integer(r->corners.board.cols, 2, 8)},
      {"board.square_mm",
       [r](const toml::node& n, const std::string& k) {
         r->corners.board.square_mm = get_double(n, k, 0.01, 1000.0);
       }},
      {"board.tracking", [r](const toml::node& n, const std::string& k) { r->tracking = get_bool(n, k); }},
      {"board.detect",
       [&s](const toml::node& n, const std::string& k) { s.processor.detect = get_bool(n, k); }},
      {"recon.mode",
       [&s](const toml::node& n, const std::string& k) {
         const auto v = get_string(n, k);
         if (const auto m = base::enum_parse(app::kReconModeNames, v))
           s.processor.mode = *m;
         else
           fail(k, "expected one of " + base::enum_names(app::kReconModeNames) + ", got \"" + v + "\"");
       }},
      {"recon.threads", integer(s.processor.threads, 1, 2)},
      {"sensor.fixed_pattern",
       [&s, base](const toml::node& n, const std::string& k) {
         s.processor.fixed_pattern = resolve(base, get_string(n, k));
       }},
      {"pipeline.stall_timeout_ms", integer(s.stall_timeout_ms, 10, 3'600'000)},
      {"pipeline.history", integer(s.history, 4, 4096)},
      {"pipeline.sse_queue_depth", integer(s.sse_queue_depth, 2, 4096)},
      {"pipeline.sse_max_clients", integer(s.sse_max_clients, 1, 64)},
      {"pipeline.frame_snapshot_interval_ms", integer(s.frame_snapshot_interval_ms, 0, 60'000)},
      {"log.level",
       [&s](const toml::node& n, const std::string& k) {
         const auto v = get_string(n, k);
         if (spdlog::level::from_str(v) == spdlog::level::off && v != "off") {
           fail(k, "expected one of trace, debug, info, warn, error, critical, off, got \"" + v + "\"");
         }
         s.log_level = v;
       }},
  };
}

void apply(const toml::table& table, const std::string& prefix, std::map<std::string, Setter>& known) {
  for (auto&& [k, node] : table) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (auto it = known.find(key); it != known.end()) {
      it->second(node, key);
    } else if (const auto* sub = node.as_table(); sub && prefix.empty()) {
      bool section_known = false;
      for (const auto& [name, _] : known) section_known |= name.rfind(key + ".", 0) == 0;
      if (!section_known) fail(key, "unknown section");
      apply(*sub, key, known);
    } else {
      fail(key, "unknown key");
    }
  }
}

}  // namespace

Settings parse_settings(const std::string& toml_text, const std::filesystem::path& base_dir) {
  toml::table table;
  try {
    table = toml::parse(toml_text);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << "TOML syntax error at line " << e.source().begin.line << ", column " << e.source().begin.column
       << ": " << e.description();
    throw SettingsError(os.str());
  }
  Settings s;
  auto known = setters(s, base_dir);
  apply(table, "", known);
  // The step's own rules (the files and cross-section rules wait for validate(): flags may override).
  if (auto why = s.processor.check(); !why.empty()) throw SettingsError(why);
  return s;
}

Settings load_settings(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw SettingsError(file.string() + ": cannot be read");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return parse_settings(text.str(), std::filesystem::absolute(file).lexically_normal().parent_path());
  } catch (const SettingsError& e) {
    throw SettingsError(file.string() + ": " + e.what());
  }
}

void parse_listen(const std::string& value, const std::string& key, std::string& host, int& port) {
  const auto colon = value.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == value.size()) {
    fail(key, "expected HOST:PORT, got \"" + value + "\"");
  }
  std::string h = value.substr(0, colon);
  if (h.size() > 2 && h.front() == '[' && h.back() == ']') h = h.substr(1, h.size() - 2);
  const std::string p = value.substr(colon + 1);
  int parsed = 0;
  for (char c : p) {
    if (c < '0' || c > '9' || parsed > 65535)
      fail(key, "port must be a number in 0..65535, got \"" + p + "\"");
    parsed = parsed * 10 + (c - '0');
  }
  if (parsed > 65535) fail(key, "port must be a number in 0..65535, got \"" + p + "\"");
  host = h;
  port = parsed;
}

std::string Settings::check() const {
  const auto no_file = [](const std::filesystem::path& f) { return !std::filesystem::is_regular_file(f); };
  const auto problem = [](const std::string& key, const std::string& what) { return key + ": " + what; };
  if (source_uri.empty()) return problem("source.uri", "must not be empty");
  if (calibration.empty()) return problem("calibration.path", "is required");
  for (const auto& f : calibration)
    if (no_file(f)) return problem("calibration.path", "no such file: " + f.string());
  if (source_uri == "auto" && !sample_capture.empty() && no_file(sample_capture))
    return problem("source.sample_capture", "no such file: " + sample_capture.string());
  if (http_host.empty()) return problem("http.host", "must not be empty");
  if (!http_token_file.empty() && no_file(http_token_file))
    return problem("http.token_file", "no such file: " + http_token_file.string());
  if (http_tls_cert.empty() != http_tls_key.empty())
    return problem(http_tls_cert.empty() ? "http.tls_cert" : "http.tls_key",
                   "http.tls_cert and http.tls_key go together");
  for (const auto& [key, f] :
       {std::pair{"http.tls_cert", &http_tls_cert}, std::pair{"http.tls_key", &http_tls_key}})
    if (!f->empty() && no_file(*f)) return problem(key, "no such file: " + f->string());
  if (sse_max_clients >= http_threads) {
    return problem("pipeline.sse_max_clients",
                   "must be below http.threads (each event stream holds a thread), got " +
                       std::to_string(sse_max_clients) + " >= " + std::to_string(http_threads));
  }
  return processor.check();
}

void validate(const Settings& s) {
  if (auto why = s.check(); !why.empty()) throw SettingsError(why);
}

}  // namespace naneye::daemon
