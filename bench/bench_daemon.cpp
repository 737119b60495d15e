// naneyed's figures (printed, never asserted): allocations per frame in the capture + processing
// path, capture-to-published latency replaying at 62 fps, requests/s on /v1/depth while streaming
// (with the dropped-pair counter before and after), steady RSS of the real naneyed process.
//
//   build/bench/bench_daemon [seconds_per_phase=5] [client_threads=2]
// clang-format off
#include <Eigen/Core>  // before httplib.h (its <resolv.h> defines `_res`, which Eigen trips on)
#include <httplib.h>
// clang-format on
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>
#include <vector>

#include "../tests/daemon/capture.hpp"
#include "../tests/daemon/temp_dir.hpp"
#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/result_json.hpp"
#include "naneye/daemon/source_select.hpp"
#include "naneye/recon/calibration_io.hpp"

extern char** environ;

// Every heap allocation of the process is counted (all threads).
static std::atomic<std::uint64_t> g_allocations{0};
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
// GCC cannot see that the operator new above is malloc-based.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

using namespace naneye;
using namespace naneye::daemon::test;

namespace {

const std::string kCalib = std::string(NANEYE_SOURCE_DIR) + "/config/calib/paper-d3.yaml";

void allocations_per_frame(const std::filesystem::path& capture, int pairs) {
  daemon::Settings settings;
  settings.history = 64;
  daemon::Pipeline pipeline(settings, daemon::make_processor(settings), daemon::driver_source_factory(),
                            {"file://" + capture.string() + "?speed=max", "bench", false},
                            std::make_shared<const recon::StereoRig>(recon::load_rig(kCalib)));
  pipeline.start();
  auto wait_for = [&](std::uint64_t n) {
    while (pipeline.pairs_processed() < n) std::this_thread::sleep_for(std::chrono::microseconds(200));
  };
  const std::uint64_t warm = 20;
  wait_for(warm);
  const auto a0 = g_allocations.load();
  const auto t0 = std::chrono::steady_clock::now();
  wait_for(static_cast<std::uint64_t>(pairs));
  const auto a1 = g_allocations.load();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto n = static_cast<double>(pairs - static_cast<int>(warm));
  std::printf(
      "allocations per frame (max-speed replay, source + worker, whole process): %.3f (%llu over %d pairs)\n",
      static_cast<double>(a1 - a0) / n, static_cast<unsigned long long>(a1 - a0),
      pairs - static_cast<int>(warm));
  std::printf(
      "max-speed replay through the pipeline: %.0f pairs/s (parse + pair + process + publish + frame copy)\n",
      n / s);
  pipeline.stop();
}

void serialization_cost() {
  // The JSON of a full board (48 valid corners), as /v1/depth and /v1/events write it.
  recon::PairResult r;
  r.board_found = true;
  r.point_count = 48;
  for (int i = 0; i < 48; ++i) {
    auto& p = r.points[static_cast<std::size_t>(i)];
    p.id = i, p.row = i / 8, p.col = i % 8, p.valid = true;
    p.left_px = {10.0 + 3.1 * i, 20.0 + 1.7 * i};
    p.right_px = p.left_px + Eigen::Vector2d(1.25, 0.5);
    p.xyz_mm = {0.1 * i, 0.2 * i, 70.0 + 0.01 * i};
    p.xyz_board_mm = p.xyz_mm;
    p.depth_sigma_mm = 0.3;
  }
  r.board = recon::BoardResult{};
  r.metrics = recon::MetricsResult{};
  const int reps = 2000;
  std::size_t bytes = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < reps; ++k) bytes += daemon::result_to_json(r).dump().size();
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / reps;
  std::printf("JSON of a 48-corner result: %.1f us, %zu bytes (done once per new result per HTTP thread)\n",
              us, bytes / reps);
}

struct Child {
  pid_t pid = -1;
  ~Child() {
    if (pid > 0) {
      kill(pid, SIGTERM);
      waitpid(pid, nullptr, 0);
    }
  }
};

long rss_kb(pid_t pid, const char* key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) == 0) return std::stol(line.substr(std::string(key).size()));
  }
  return -1;
}

void service_figures(const std::filesystem::path& dir, const std::filesystem::path& capture, double seconds,
                     int threads) {
  const auto log = dir / "naneyed.log";
  std::vector<std::string> args{NANEYED_PATH,
                                "--calib",
                                kCalib,
                                "--listen",
                                "127.0.0.1:0",
                                "--source",
                                "file://" + capture.string() + "?speed=realtime&loop=1"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  Child child;
  posix_spawn(&child.pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  int port = 0;
  const std::regex re(R"(listening on http://[^:]+:(\d+)/)");
  for (int i = 0; i < 1000 && port == 0; ++i) {
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    std::smatch m;
    const std::string s = text.str();
    if (std::regex_search(s, m, re)) port = std::stoi(m[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (port == 0) {
    std::printf("naneyed did not start; see %s\n", log.c_str());
    return;
  }
  httplib::Client c("127.0.0.1", port);
  auto status = [&] { return nlohmann::json::parse(c.Get("/v1/status")->body); };

  // Phase 1: streaming at 62 fps, no HTTP load.
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  auto s1 = status();
  std::printf(
      "naneyed replaying at %.1f fps: capture-to-published p50 %.3f ms, p99 %.3f ms, max %.3f ms (%d pairs); "
      "processing p50 %.4f ms p99 %.4f ms\n",
      s1["fps"]["left"].get<double>(), s1["capture_to_publish_ms"]["p50"].get<double>(),
      s1["capture_to_publish_ms"]["p99"].get<double>(), s1["capture_to_publish_ms"]["max"].get<double>(),
      s1["capture_to_publish_ms"]["samples"].get<int>(), s1["recon_ms"]["p50"].get<double>(),
      s1["recon_ms"]["p99"].get<double>());
  const long rss_before = rss_kb(child.pid, "VmRSS:");

  // Phase 2: keep-alive clients hammering /v1/depth while it streams.
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> ok{0}, failed{0};
  std::vector<std::thread> clients;
  for (int t = 0; t < threads; ++t) {
    clients.emplace_back([&] {
      httplib::Client cl("127.0.0.1", port);
      cl.set_keep_alive(true);
      cl.set_tcp_nodelay(true);
      while (!stop.load(std::memory_order_relaxed)) {
        auto r = cl.Get("/v1/depth");
        (r && r->status == 200 ? ok : failed).fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  stop.store(true);
  for (auto& t : clients) t.join();
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto s2 = status();
  std::printf(
      "/v1/depth under load (%d keep-alive client threads in this process, same 2 cores): %.0f req/s, %llu "
      "failed; pairs processed during the load %lld, dropped pairs before %lld after %lld; "
      "capture-to-published "
      "p99 %.3f ms\n",
      threads, static_cast<double>(ok.load()) / el, static_cast<unsigned long long>(failed.load()),
      s2["pairs"]["processed"].get<long long>() - s1["pairs"]["processed"].get<long long>(),
      s1["counters"]["pairs_dropped"].get<long long>(), s2["counters"]["pairs_dropped"].get<long long>(),
      s2["capture_to_publish_ms"]["p99"].get<double>());
  std::printf(
      "naneyed RSS: %ld kB after %.0f s streaming, %ld kB after the load (anonymous %ld kB, file-backed "
      "i.e. shared libraries %ld kB), peak %ld kB\n",
      rss_before, seconds, rss_kb(child.pid, "VmRSS:"), rss_kb(child.pid, "RssAnon:"),
      rss_kb(child.pid, "RssFile:"), rss_kb(child.pid, "VmHWM:"));
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 5.0;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 2;
  TempDir dir;
  const int pairs = 124;  // two seconds of 62 fps
  const auto capture = dir.path / "bench.raw";
  write_capture(capture, pairs, 62.0);
  allocations_per_frame(capture, pairs);
  serialization_cost();
  service_figures(dir.path, capture, seconds, threads);
  return 0;
}
