#include "config_check.hpp"

#include <sys/stat.h>

#include <chrono>

#include "http_access.hpp"
#include "naneye/app/fixed_pattern_step.hpp"
#include "naneye/driver/source_uri.hpp"

namespace naneye::daemon {
namespace {

// A path as a file:// URI target: percent-encodes what parse_uri would read as syntax.
std::string uri_path(const std::string& path) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : path) {
    if (c == '%' || c == '?' || c == '#' || c == '&' || c <= 0x20 || c >= 0x7f) {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

// A capture must deliver at least one stereo pair: an empty file or random bytes replay nothing
// and would leave the daemon "streaming" nothing. Replayed at full speed until the first pair
// (a capture of any size answers within its first two records).
void check_capture(const std::string& path, const std::string& key, const driver::SourceRegistry& registry,
                   std::vector<std::string>& problems) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    problems.push_back(key + ": no such file: " + path);
    return;
  }
  try {
    auto src = registry.open("file://" + uri_path(path) + "?speed=max");
    src->start();
    // 10 s: far more than two records take to parse from any disk; a guard, not a measurement.
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    bool pair = false;
    while (!pair && std::chrono::steady_clock::now() < until) {
      pair = src->next(std::chrono::milliseconds(100)) != nullptr;
      if (!pair && driver::has_ended(src->state())) break;
    }
    const auto records = src->counters().records;
    const auto err = src->error();
    src->stop();
    if (!pair) {
      problems.push_back(key + ": " + path + " holds no complete stereo pair (" + std::to_string(st.st_size) +
                         " bytes, " + std::to_string(records) + " records" + (err ? ": " + *err : "") +
                         "): empty, or not a NanEye capture");
    }
  } catch (const std::exception& e) {
    problems.push_back(key + ": " + e.what());
  }
}

}  // namespace

std::vector<std::string> check_config(const Settings& s, const driver::SourceRegistry& registry) {
  std::vector<std::string> problems;
  http::check_access_files(s, problems);
  if (!s.processor.fixed_pattern.empty()) {
    try {
      app::FixedPatternStep(s.processor.fixed_pattern, driver::kSensorSize, driver::kSensorSize);
    } catch (const std::exception& e) {
      problems.push_back(std::string("sensor.fixed_pattern: ") + e.what());
    }
  }
  if (s.source_uri == "auto") {
    if (!s.sample_capture.empty())
      check_capture(s.sample_capture.string(), "source.sample_capture", registry, problems);
  } else {
    try {
      const auto uri = driver::parse_uri(s.source_uri);
      if (!registry.has(uri.scheme)) {
        std::string known;
        for (const auto& k : registry.schemes()) known += (known.empty() ? "" : ", ") + k + "://";
        problems.push_back("source.uri: unknown scheme \"" + uri.scheme + "\" (known: auto, " + known + ")");
      } else if (uri.scheme == "usb") {
        driver::parse_usb_uri(uri);
      } else if (uri.scheme == "v4l2") {
        const auto v = driver::parse_v4l2_uri(uri);
        struct stat st {};
        if (::stat(v.device.c_str(), &st) != 0 || !S_ISCHR(st.st_mode))
          problems.push_back("source.uri: " + v.device + " is not a character device (no V4L2 node there)");
      } else if (uri.scheme == "file") {
        const auto f = driver::parse_file_uri(uri);
        check_capture(f.path, "source.uri", registry, problems);
      }
    } catch (const std::exception& e) {
      problems.push_back(std::string("source.uri: ") + e.what());
    }
  }
  return problems;
}

}  // namespace naneye::daemon
