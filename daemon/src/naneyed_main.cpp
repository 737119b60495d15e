// naneyed: serves depth from the NanEye Stereo camera over HTTP (docs/http-api.md).
//
// The main thread is the supervisor: it blocks SIGTERM/SIGINT/SIGHUP before any thread exists and
// takes them synchronously with sigtimedwait (no work in signal handlers), and it feeds the systemd
// watchdog only while the pipeline makes progress or waits for its device.
#include <malloc.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <CLI/CLI.hpp>
#include <cstdlib>
#include <iostream>

#include "config_check.hpp"
#include "http_server.hpp"
#include "log.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/app/sources.hpp"
#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/rig_check.hpp"
#include "naneye/daemon/settings.hpp"
#include "naneye/daemon/source_select.hpp"
#include "naneye/driver/wire_format.hpp"
#include "naneye/recon/camera/calibration_io.hpp"

namespace {

using namespace naneye;

struct Flags {
  std::string config = NANEYE_DEFAULT_CONFIG;
  bool config_given = false;
  std::string source, listen, log_level;
  std::vector<std::string> calib;
  bool check = false;
};

daemon::Settings load(const Flags& f) {
  daemon::Settings s;
  if (f.config_given || std::filesystem::exists(f.config)) s = daemon::load_settings(f.config);
  if (!f.source.empty()) s.source_uri = f.source;
  if (!f.calib.empty()) s.calibration.assign(f.calib.begin(), f.calib.end());
  if (!f.listen.empty()) daemon::parse_listen(f.listen, "--listen", s.http_host, s.http_port);
  if (!f.log_level.empty()) {
    if (spdlog::level::from_str(f.log_level) == spdlog::level::off && f.log_level != "off") {
      throw daemon::SettingsError("--log-level: expected trace, debug, info, warn, error, critical or off");
    }
    s.log_level = f.log_level;
  }
  daemon::validate(s);
  return s;
}

void watchdog_and_signals(daemon::Pipeline& pipeline, daemon::HttpServer& server,
                          const daemon::Settings& settings) {
  std::uint64_t usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &usec) > 0;
  const auto tick =
      std::chrono::microseconds(watchdog ? std::min<std::uint64_t>(usec / 2, 100'000) : 100'000);
  const auto kick_every = std::chrono::microseconds(watchdog ? usec / 2 : 0);
  sigset_t set;
  sigemptyset(&set);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, s);
  auto last_kick = std::chrono::steady_clock::now();
  std::uint64_t beat = pipeline.heartbeat(), processed = pipeline.pairs_processed();
  for (;;) {
    timespec ts{0, static_cast<long>(std::chrono::nanoseconds(tick).count())};
    const int sig = sigtimedwait(&set, nullptr, &ts);
    if (sig == SIGTERM || sig == SIGINT) {
      daemon::log()->info("{}: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
      return;
    }
    if (sig == SIGHUP) {
      sd_notify(0, "RELOADING=1");
      std::string why;
      try {
        auto rig = std::make_shared<const recon::StereoRig>(recon::load_rig(settings.calibration));
        if (auto problem = daemon::rig_problem(*rig, driver::kSensorSize)) {
          why = *problem;
        } else {
          // The new maps are built here, not on the worker: it only swaps the processor in.
          auto prepared = app::make_processor(settings.processor);
          prepared->set_rig(*rig);
          pipeline.reload(std::move(rig), std::move(prepared));
        }
      } catch (const std::exception& e) {
        why = e.what();
      }
      if (!why.empty()) {
        daemon::log()->error("SIGHUP: calibration not reloaded, keeping the current one: {}", why);
        pipeline.reload_refused(why);
      }
      // The token file and the certificate, each on its own: a bad one keeps its predecessor and
      // stops neither the calibration's reload nor the other's.
      server.reload_access(pipeline.status().uptime_s);
      sd_notify(0, "READY=1");
    }
    // The processor a reload replaced is freed here, and the pages it and the reload's parsing
    // leave free go back to the system: glibc keeps freed memory in each thread's arena, so a
    // SIGHUP storm grew the anonymous RSS by 7.5 MB (TLS: 18 MB) before it levelled off
    // (docs/reliability.md, "Attacks").
    if (pipeline.release_retired_processor() || sig == SIGHUP) malloc_trim(0);
    const auto now = std::chrono::steady_clock::now();
    if (watchdog && now - last_kick >= kick_every) {
      const auto b = pipeline.heartbeat(), p = pipeline.pairs_processed();
      const auto st = pipeline.status().state;
      // Alive is not enough: the worker must be turning and either producing or waiting for a device.
      if (b != beat && (p != processed || st == daemon::ServiceState::waiting_for_device)) {
        sd_notify(0, "WATCHDOG=1");
        last_kick = now;
      }
      beat = b, processed = p;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Flags f;
  CLI::App app{"naneyed: NanEye Stereo depth service (HTTP/JSON, docs/http-api.md)"};
  app.add_option("--config", f.config, "TOML configuration file")->default_str(NANEYE_DEFAULT_CONFIG);
  app.add_option("--source", f.source,
                 "source URI (overrides source.uri): auto, usb://, v4l2://, file://, sim://");
  app.add_option("--calib", f.calib, "calibration file(s) (overrides calibration.path)");
  app.add_option("--listen", f.listen, "HOST:PORT to serve on (overrides http.host/http.port; port 0: any)");
  app.add_option("--log-level", f.log_level, "trace, debug, info, warn, error, critical, off");
  app.add_flag("--check-config", f.check, "validate the configuration and exit (0: valid, 1: not)");
  CLI11_PARSE(app, argc, argv);
  f.config_given = app.count("--config") > 0;

  const auto logger = base::program_logger("daemon");
  daemon::Settings settings;
  std::shared_ptr<const recon::StereoRig> rig;
  try {
    settings = load(f);
    rig = std::make_shared<const recon::StereoRig>(recon::load_rig(settings.calibration));
    if (auto problem = daemon::rig_problem(*rig, driver::kSensorSize)) {
      throw std::runtime_error("calibration cannot be used: " + *problem);
    }
  } catch (const std::exception& e) {
    std::cerr << "naneyed: error: " << e.what() << "\n";
    return 1;
  }
  if (f.check) {
    const auto problems = daemon::check_config(settings, app::make_source_registry());
    for (const auto& p : problems) std::cerr << "naneyed: error: " << p << "\n";
    if (!problems.empty()) return 1;
    std::cout << "naneyed: configuration OK (source " << settings.source_uri << ", listen "
              << settings.http_host << ":" << settings.http_port << ", baseline " << rig->baseline_mm()
              << " mm)\n";
    return 0;
  }
  logger->set_level(spdlog::level::from_str(settings.log_level));

  // Before any thread starts, so that every thread inherits the mask and only sigtimedwait sees them.
  sigset_t set;
  sigemptyset(&set);
  for (int s : {SIGTERM, SIGINT, SIGHUP}) sigaddset(&set, s);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  signal(SIGPIPE, SIG_IGN);

  try {
    const auto choice = daemon::choose_source(settings, [] { return app::attached_boards(); });
    logger->info("source: {} ({})", choice.uri, choice.reason);
    auto processor = app::make_processor(settings.processor);
    logger->info("processing step: {}", processor->name());
    daemon::Pipeline pipeline(settings, std::move(processor), daemon::driver_source_factory(), choice, rig);
    daemon::HttpServer server(settings, pipeline, NANEYE_VERSION);
    const int port = server.bind();
    server.start();
    pipeline.start();
    logger->info("listening on {}://{}:{}/ (try /v1/status, /v1/depth)",
                 settings.http_tls_cert.empty() ? "http" : "https", settings.http_host, port);
    sd_notifyf(0, "READY=1\nSTATUS=serving on %s:%d, source %s", settings.http_host.c_str(), port,
               choice.uri.c_str());

    watchdog_and_signals(pipeline, server, settings);

    sd_notify(0, "STOPPING=1");
    const auto t0 = std::chrono::steady_clock::now();
    pipeline.stop();
    const bool closed = server.stop(std::chrono::milliseconds(400));
    const auto ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    logger->info("stopped in {:.0f} ms after {} pairs", ms, pipeline.pairs_processed());
    if (!closed) {
      // An idle keep-alive client still holds an HTTP thread; do not wait for it to time out.
      logger->info("HTTP connections still open at exit, closed by the kernel");
      logger->flush();
      std::_Exit(0);
    }
  } catch (const std::exception& e) {
    logger->error("{}", e.what());
    return 1;
  }
  return 0;
}
