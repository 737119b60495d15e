// naneyed's figures (printed, never asserted), on a temporally smooth rendered capture (the board
// orbiting at ~70 mm, replayed at 62 fps: bench/smooth_capture.hpp) with the REAL processing step
// (BoardReconstruction: corners, triangulation, board pose, P/D/R) and, as a second row, the
// timing-only step (board.detect = false), then [recon] mode both (board + sparse + dense scene) on a
// textured scene (the hand-held sphere, bench/smooth_capture.hpp) and on the board capture:
//  - allocations per frame on the reconstruction worker and on the other threads (capture, the
//    scene's helper; in-process Pipeline, max-speed replay; every operator new counted per thread);
//  - naneyed itself: capture-to-published latency p50/p99; requests/s on /v1/depth while streaming,
//    from keep-alive connections driven by one epoll thread (bench/http_load.hpp: it costs far less
//    per request than the server, unlike httplib's client), counted by the client and by naneyed
//    (naneye_depth_served_total), with request latency, the dropped-pair counter before and after,
//    and where the cores' time went (naneyed, the client, other processes: the machine is shared);
//    steady RSS.
//
//   build/bench/bench_daemon [seconds_per_phase=5] [connections=8] [--quick] [--scene-only] [--threads N]
// (--threads: the scene phases' [recon] threads, default the daemon's)
// More connections than naneyed's http.threads (8) wait for a thread: httplib serves a connection
// on one pool thread until it closes (after 100 requests or 1 s idle).
// clang-format off
#include <Eigen/Core>  // before httplib.h (its <resolv.h> defines `_res`, which Eigen trips on)
#include <httplib.h>
// clang-format on
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <new>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <vector>

#include "../tests/daemon/daemon_process.hpp"
#include "../tests/daemon/temp_dir.hpp"
#include "http_load.hpp"
#include "naneye/app/processor.hpp"
#include "naneye/app/result_json.hpp"
#include "naneye/daemon/pipeline.hpp"
#include "naneye/daemon/source_select.hpp"
#include "naneye/recon/camera/calibration_io.hpp"
#include "smooth_capture.hpp"

// Every heap allocation of the process is counted, in total and per thread: each thread takes a
// slot of a fixed table on its first allocation (no allocation of its own, no lock).
static std::atomic<std::uint64_t> g_allocations{0};
constexpr int kSlots = 64;
static std::atomic<std::uint64_t> g_slot_allocations[kSlots];
static std::atomic<int> g_next_slot{0};
static thread_local int t_slot = -1;
static int thread_slot() {
  if (t_slot < 0) t_slot = std::min(g_next_slot.fetch_add(1, std::memory_order_relaxed), kSlots - 1);
  return t_slot;
}
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_slot_allocations[thread_slot()].fetch_add(1, std::memory_order_relaxed);
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

// The real processing step, unchanged, with the worker thread's slot noted (the first call).
class TaggingProcessor final : public app::PairProcessor {
 public:
  explicit TaggingProcessor(std::unique_ptr<app::PairProcessor> inner) : inner_(std::move(inner)) {}
  void set_rig(const recon::StereoRig& rig) override { inner_->set_rig(rig); }
  void process(const driver::StereoPair& pair, recon::PairResult& out) override {
    worker_slot.store(thread_slot(), std::memory_order_relaxed);
    inner_->process(pair, out);
    found += out.board_found;
  }
  void process_pair(const driver::StereoPair& pair, recon::PairResult& out, app::SceneResult& scene,
                    recon::scene::DepthMap* depth) override {
    worker_slot.store(thread_slot(), std::memory_order_relaxed);
    inner_->process_pair(pair, out, scene, depth);
    found += out.board_found;
    scene_valid += scene.sparse.valid_count;
  }
  bool scene() const override { return inner_->scene(); }
  bool dense() const override { return inner_->dense(); }
  void reserve(app::SceneResult& scene, recon::scene::DepthMap* depth) const override {
    inner_->reserve(scene, depth);
  }
  std::string_view name() const override { return inner_->name(); }
  std::atomic<long> scene_valid{0};
  std::atomic<int> worker_slot{-1};
  std::atomic<int> found{0};

 private:
  std::unique_ptr<app::PairProcessor> inner_;
};

std::array<std::uint64_t, kSlots> slot_counts() {
  std::array<std::uint64_t, kSlots> c{};
  for (int i = 0; i < kSlots; ++i) c[static_cast<std::size_t>(i)] = g_slot_allocations[i].load();
  return c;
}

void allocations_per_frame(const std::filesystem::path& capture, int pairs, bool detect,
                           app::ReconMode mode = app::ReconMode::board, const char* what = nullptr,
                           int threads = app::ProcessorSettings{}.threads) {
  daemon::Settings settings;
  settings.history = 64;
  settings.processor.detect = detect;
  settings.processor.mode = mode;
  settings.processor.threads = threads;
  auto tagging = std::make_unique<TaggingProcessor>(app::make_processor(settings.processor));
  TaggingProcessor& tag = *tagging;
  daemon::Pipeline pipeline(settings, std::move(tagging), daemon::driver_source_factory(),
                            {"file://" + capture.string() + "?speed=max", "bench", false},
                            std::make_shared<const recon::StereoRig>(recon::load_rig(kCalib)));
  const int main_slot = thread_slot();
  pipeline.start();
  auto wait_for = [&](std::uint64_t n) {
    while (pipeline.pairs_processed() < n) std::this_thread::sleep_for(std::chrono::microseconds(200));
  };
  const std::uint64_t warm = 20;
  wait_for(warm);
  const auto c0 = slot_counts();
  const int found0 = tag.found.load();
  const long scene0 = tag.scene_valid.load();
  const auto t0 = std::chrono::steady_clock::now();
  wait_for(static_cast<std::uint64_t>(pairs));
  const auto c1 = slot_counts();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto n = static_cast<double>(pairs - static_cast<int>(warm));
  const int worker = tag.worker_slot.load();
  std::uint64_t in_worker = 0, in_others = 0;
  for (int i = 0; i < kSlots; ++i) {
    const auto d = c1[static_cast<std::size_t>(i)] - c0[static_cast<std::size_t>(i)];
    if (i == worker)
      in_worker += d;
    else if (i != main_slot)
      in_others += d;
  }
  std::printf(
      "%-40s allocations per frame: recon worker %.2f, capture and helper threads %.2f (%.0f pairs after "
      "%llu warm-up, %d with a board, %.0f valid scene points per pair); max-speed replay %.0f pairs/s\n",
      what     ? what
      : detect ? "in-process Pipeline, BoardReconstruction:"
               : "in-process Pipeline, timing only:",
      static_cast<double>(in_worker) / n, static_cast<double>(in_others) / n, n,
      static_cast<unsigned long long>(warm), tag.found.load() - found0,
      static_cast<double>(tag.scene_valid.load() - scene0) / n, n / s);
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
  for (int k = 0; k < reps; ++k) bytes += app::result_to_json(r).dump().size();
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / reps;
  std::printf(
      "JSON of a 48-corner result: %.1f us, %zu bytes (done once per new result, shared by the HTTP "
      "threads)\n",
      us, bytes / reps);
}

long rss_kb(pid_t pid, const char* key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) == 0) return std::stol(line.substr(std::string(key).size()));
  }
  return -1;
}

// CPU seconds (user + system) of naneyed, of this process, and of the whole machine, read from /proc.
struct CpuSample {
  double wall_s = 0, naneyed_s = 0, self_s = 0, machine_busy_s = 0, machine_idle_s = 0;
};

double proc_cpu_s(const std::string& stat_path) {
  std::ifstream in(stat_path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Fields after the command name, which is in parentheses and may hold spaces.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string f;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> f; ++i)
    if (i >= 14) ticks += std::stod(f);  // utime, stime
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

CpuSample cpu_now(pid_t naneyed) {
  CpuSample s;
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  s.naneyed_s = proc_cpu_s("/proc/" + std::to_string(naneyed) + "/stat");
  s.self_s = proc_cpu_s("/proc/self/stat");
  std::ifstream in("/proc/stat");
  std::string cpu;
  double v[8] = {};  // user nice system idle iowait irq softirq steal
  in >> cpu;
  for (double& x : v) in >> x;
  const double tick = static_cast<double>(sysconf(_SC_CLK_TCK));
  s.machine_idle_s = (v[3] + v[4]) / tick;
  s.machine_busy_s = (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / tick;
  return s;
}

// A counter from naneyed's /metrics ("name value" line).
double metric(httplib::Client& c, const std::string& name) {
  const auto m = c.Get("/metrics");
  if (!m) return 0;
  const auto at = m->body.find("\n" + name + " ");
  return at == std::string::npos ? 0 : std::atof(m->body.c_str() + at + name.size() + 2);
}

void service_figures(const std::filesystem::path& dir, const std::filesystem::path& capture, double seconds,
                     int connections, bool detect, app::ReconMode mode = app::ReconMode::board,
                     const char* what = nullptr, int threads = app::ProcessorSettings{}.threads) {
  const auto log = dir / "naneyed.log";
  const auto config = dir / "naneyed.toml";
  std::ofstream(config) << "[board]\ndetect = " << (detect ? "true" : "false") << "\n[recon]\nmode = \""
                        << app::to_string(mode) << "\"\nthreads = " << threads << "\n";
  std::printf("-- naneyed, %s\n", what     ? what
                                  : detect ? "board reconstruction (the real processing step)"
                                           : "timing only (board.detect = false)");
  daemon::test::DaemonProcess child(
      {"--config", config.string(), "--calib", kCalib, "--listen", "127.0.0.1:0", "--source",
       "file://" + capture.string() + "?speed=realtime&loop=1"},
      log);
  const std::optional<int> listening = child.wait_port();
  if (!listening) {
    std::printf("naneyed did not start; see %s\n", log.c_str());
    return;
  }
  const int port = *listening;
  httplib::Client c("127.0.0.1", port);
  auto status = [&] { return nlohmann::json::parse(c.Get("/v1/status")->body); };

  // Phase 1: streaming at 62 fps, no HTTP load.
  const auto idle0 = cpu_now(child.pid());
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  const auto idle1 = cpu_now(child.pid());
  const double streaming_share = (idle1.naneyed_s - idle0.naneyed_s) / (idle1.wall_s - idle0.wall_s);
  auto s1 = status();
  std::printf(
      "naneyed replaying at %.1f fps: capture-to-published p50 %.3f ms, p99 %.3f ms, max %.3f ms (%d pairs); "
      "processing p50 %.4f ms p99 %.4f ms; pairs processed %lld, superseded by a newer one %lld\n",
      s1["fps"]["left"].get<double>(), s1["capture_to_publish_ms"]["p50"].get<double>(),
      s1["capture_to_publish_ms"]["p99"].get<double>(), s1["capture_to_publish_ms"]["max"].get<double>(),
      s1["capture_to_publish_ms"]["samples"].get<int>(), s1["recon_ms"]["p50"].get<double>(),
      s1["recon_ms"]["p99"].get<double>(), s1["pairs"]["processed"].get<long long>(),
      s1["pairs"]["superseded"].get<long long>());
  const long rss_before = rss_kb(child.pid(), "VmRSS:");
  if (auto d = c.Get("/v1/depth"); d && d->status == 200) {
    const auto j = nlohmann::json::parse(d->body);
    std::printf("latest /v1/depth: pair %lld, board_found %s, %s, %zu bytes\n", j["pair"].get<long long>(),
                j["board_found"].get<bool>() ? "true" : "false",
                j.contains("scene")
                    ? (std::to_string(j["scene"]["valid_points"].get<int>()) + " valid scene points" +
                       (j["scene"]["depth"].is_null() ? ", no dense map" : ", a dense map"))
                          .c_str()
                    : "no scene",
                d->body.size());
  }

  // Phase 2: keep-alive connections hammering /v1/depth while it streams. The rate is given as the
  // client counted it and as naneyed counted it (naneye_depth_served_total), with where the two
  // cores' time went during the load.
  const auto served0 = metric(c, "naneye_depth_served_total");
  const auto cpu0 = cpu_now(child.pid());
  auto load = bench::http_load(port, "/v1/depth", connections, seconds);
  const auto cpu1 = cpu_now(child.pid());
  const auto served1 = metric(c, "naneye_depth_served_total");
  auto s2 = status();
  const double el = load.seconds;
  const double per_s = static_cast<double>(load.ok) / el;
  std::printf(
      "/v1/depth under load (%d keep-alive connections, one request in flight each, from one epoll thread "
      "of this process on the same cores): %.0f req/s by the client, %.0f req/s by naneyed's "
      "naneye_depth_served_total, %llu failed, %llu connections opened; request latency p50 %.3f ms p99 "
      "%.3f ms\n",
      connections, per_s, (served1 - served0) / el, static_cast<unsigned long long>(load.failed),
      static_cast<unsigned long long>(load.connects), load.percentile_ms(0.50), load.percentile_ms(0.99));
  const double wall = cpu1.wall_s - cpu0.wall_s;
  const double naneyed_s = cpu1.naneyed_s - cpu0.naneyed_s, self_s = cpu1.self_s - cpu0.self_s;
  const double busy_s = cpu1.machine_busy_s - cpu0.machine_busy_s;
  const double total_s = busy_s + cpu1.machine_idle_s - cpu0.machine_idle_s;
  const double http_s = naneyed_s - streaming_share * wall;  // above what streaming alone took
  std::printf(
      "CPU during the load, %% of one core (the machine has %ld cores, shared): naneyed %.0f%% (streaming "
      "alone "
      "took %.0f%%: the HTTP side %.1f us per request), load client %.0f%% (%.1f us per request), other "
      "processes %.0f%%, idle %.0f%%\n",
      sysconf(_SC_NPROCESSORS_ONLN), 100 * naneyed_s / wall, 100 * streaming_share,
      1e6 * http_s / static_cast<double>(load.ok), 100 * load.cpu_seconds / wall,
      1e6 * load.cpu_seconds / static_cast<double>(load.ok),
      100 * std::max(0.0, busy_s - naneyed_s - self_s) / wall, 100 * (total_s - busy_s) / wall);
  std::printf(
      "while loaded: pairs processed %lld, dropped pairs before %lld after %lld; capture-to-published p99 "
      "%.3f "
      "ms (over the whole run)\n",
      s2["pairs"]["processed"].get<long long>() - s1["pairs"]["processed"].get<long long>(),
      s1["counters"]["pairs_dropped"].get<long long>(), s2["counters"]["pairs_dropped"].get<long long>(),
      s2["capture_to_publish_ms"]["p99"].get<double>());
  std::printf(
      "naneyed RSS: %ld kB after %.0f s streaming, %ld kB after the load (anonymous %ld kB, file-backed "
      "i.e. shared libraries %ld kB), peak %ld kB\n",
      rss_before, seconds, rss_kb(child.pid(), "VmRSS:"), rss_kb(child.pid(), "RssAnon:"),
      rss_kb(child.pid(), "RssFile:"), rss_kb(child.pid(), "VmHWM:"));
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 5.0;
  int connections = 8, rendered = 124;  // 124 poses: 2 s forwards, 2 s back (246 pairs, ~4 s per loop)
  int positional = 0, threads = app::ProcessorSettings{}.threads;
  bool scene_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      seconds = 2.0;
      rendered = 62;
    } else if (a == "--threads" && i + 1 < argc) {
      threads = std::atoi(argv[++i]);  // [recon] threads of the scene phases
    } else if (a == "--scene-only") {
      scene_only = true;  // the two [recon] mode both phases alone
    } else if (a.rfind("--", 0) == 0) {
      continue;  // scripts/bench.sh's --benchmark_* flags
    } else if (positional++ == 0) {
      seconds = std::atof(argv[i]);
    } else {
      connections = std::atoi(argv[i]);
    }
  }
  TempDir dir;
  const auto capture = dir.path / "smooth.raw";
  const int pairs = bench::write_smooth_capture(capture, rendered, 62.0);
  std::printf(
      "capture: %d pairs of the sim 'orbit' sequence (paper-d3, ~70 mm), 62 fps, forwards then back\n",
      pairs);
  // A textured scene (issue 14) along the hand-held trajectory, for [recon] mode scene / both.
  const auto scene_capture = dir.path / "scene.raw";
  const int scene_pairs = bench::write_scene_capture(scene_capture, "sphere", rendered / 2, 62.0);
  std::printf(
      "scene capture: %d pairs of the textured 'sphere' (12-20 mm), hand-held, 62 fps, forwards then back\n",
      scene_pairs);
  if (!scene_only) {
    allocations_per_frame(capture, pairs, true);
    allocations_per_frame(capture, pairs, false);
  }
  allocations_per_frame(scene_capture, std::min(scene_pairs, 60), true, app::ReconMode::both,
                        "in-process Pipeline, board + scene:", threads);
  if (!scene_only) {
    serialization_cost();
    service_figures(dir.path, capture, seconds, connections, true);
    service_figures(dir.path, capture, seconds, connections, false);
  }
  std::printf("scene phases: [recon] threads = %d\n", threads);
  service_figures(dir.path, scene_capture, seconds, connections, true, app::ReconMode::both,
                  "board + scene ([recon] mode = \"both\") on the textured sphere", threads);
  service_figures(dir.path, capture, seconds, connections, true, app::ReconMode::both,
                  "board + scene ([recon] mode = \"both\") on the board capture", threads);
  return 0;
}
