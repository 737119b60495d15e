#pragma once
// naneyed's configuration: loaded once at start from TOML (config/naneyed.toml in the tree,
// /etc/naneye/naneyed.toml when installed), then overridden by command-line flags. A plain struct;
// everything that changes while running lives in the pipeline and the server, not here.
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "naneye/app/processor.hpp"

namespace naneye::daemon {

// The shared step's names as the daemon's own code spells them (naneye_app holds them: the CLI runs
// the same step).
using app::DepthSlot;
using app::DepthSummary;
using app::PairProcessor;
using app::ReconMode;
using app::SceneResult;

struct Settings {
  // [source]
  std::string source_uri = "auto";       // "auto": first attached readout board, else `sample_capture`
  std::filesystem::path sample_capture;  // the bundled capture "auto" falls back to (looping, real-time)
  // [calibration]
  std::vector<std::filesystem::path> calibration;  // one file, or intrinsics + extrinsics
  // [http]
  std::string http_host = "127.0.0.1";
  int http_port = 8080;  // 0: an ephemeral port, logged once bound
  int http_threads = 8;  // threads running requests; each /v1/events stream holds one while open
  // Open client connections kept at most (lowered to fit the descriptor limit); past it the oldest
  // connection that has sent nothing is closed for a newcomer, or the newcomer gets 503.
  int http_max_connections = 512;
  int http_head_timeout_ms = 2000;  // a request's head and body must arrive within this (else 408)
  int http_idle_timeout_ms = 5000;  // an idle keep-alive connection is closed after this
  // Access (docs/http-api.md, "Access"): a file holding the bearer token every request must present
  // (empty: no token); a PEM certificate chain and its key to serve HTTPS (both or neither).
  std::filesystem::path http_token_file;
  std::filesystem::path http_tls_cert, http_tls_key;
  // [pipeline] (corner_sigma_px is the processor's)
  int max_result_age_ms = 500;          // /readyz fails when the latest result is older
  int stall_timeout_ms = 2000;          // no pair for this long while the source streams: "stalled"
  int history = 64;                     // results kept for /v1/events resumption (Last-Event-ID)
  int sse_queue_depth = 64;             // results queued per /v1/events client before it is dropped
  int sse_max_clients = 4;              // simultaneous /v1/events clients
  int frame_snapshot_interval_ms = 20;  // how often the latest frames are copied for /v1/frames
  // [board], [recon] mode and [pipeline] corner_sigma_px: the per-pair step's own settings (the
  // board's grid, square size and tracking, whether to detect at all, board/scene/both), with the
  // recon structs' defaults (the paper's board: 6 x 8 inner corners of 5.99 mm).
  app::ProcessorSettings processor;

  // Empty when usable, otherwise the first problem, naming the key ("calibration.path: is required"):
  // each section's rules, the cross-field ones, the referenced files, then processor.check().
  std::string check() const;
  // [log]
  std::string log_level = "info";  // trace, debug, info, warn, error, critical, off
};

// Thrown for an unreadable file, a TOML syntax error, an unknown key or a bad value; what() names
// the key (e.g. "http.port: must be in 0..65535, got 70000").
class SettingsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads `file` over the defaults. Relative paths inside it are resolved against the file's folder.
Settings load_settings(const std::filesystem::path& file);
// Parses TOML text (for tests and --check-config); `base_dir` resolves relative paths.
Settings parse_settings(const std::string& toml_text, const std::filesystem::path& base_dir);

// "HOST:PORT" (or "[v6]:PORT") -> host and port; throws SettingsError naming `key`.
void parse_listen(const std::string& value, const std::string& key, std::string& host, int& port);

// Throws SettingsError with s.check()'s problem, if any.
void validate(const Settings& s);

}  // namespace naneye::daemon
