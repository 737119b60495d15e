#pragma once
// Starts the real naneyed binary (NANEYED_PATH) on 127.0.0.1 with an ephemeral port for the
// integration tests, reads the port from its log, and stops it with a signal.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "temp_dir.hpp"

extern char** environ;

namespace naneye::daemon::test {

inline std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class DaemonProcess {
 public:
  // Runs `naneyed args...` with stderr (the log) into `log`.
  DaemonProcess(std::vector<std::string> args, std::filesystem::path log) : log_(std::move(log)) {
    std::vector<std::string> argv{NANEYED_PATH};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> cargv;
    for (auto& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 2, log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 1, (log_.string() + ".out").c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    if (posix_spawn(&pid_, cargv[0], &fa, nullptr, cargv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~DaemonProcess() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  // The PORT of the log line "listening on http[s]://HOST:PORT/", if there is one yet. (No std::regex:
  // GCC 12 trips -Wmaybe-uninitialized in it under ASan at -O2.)
  static std::optional<int> listening_port(const std::string& text) {
    const std::string scheme = "listening on http";
    const auto on = text.find(scheme);
    if (on == std::string::npos) return std::nullopt;
    const std::string key = "://";
    const auto at = text.find(key, on);
    if (at == std::string::npos) return std::nullopt;
    const auto colon = text.find(':', at + key.size());
    const auto slash = text.find('/', at + key.size());
    if (colon == std::string::npos || slash == std::string::npos || slash < colon + 2) return std::nullopt;
    try {
      return std::stoi(text.substr(colon + 1, slash - colon - 1));
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }

  // The port from "listening on http://127.0.0.1:PORT/", or empty if the daemon died first.
  std::optional<int> wait_port(std::chrono::milliseconds timeout = std::chrono::seconds(15)) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < until) {
      if (auto port = listening_port(log())) return port;
      if (waitpid(pid_, &status_, WNOHANG) == pid_) {
        exited_ = true;
        return std::nullopt;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return std::nullopt;
  }

  // Sends `sig` and waits for the exit; returns the exit code (or -signal) and the time it took.
  std::pair<int, std::chrono::milliseconds> stop(
      int sig, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    const auto t0 = std::chrono::steady_clock::now();
    kill(pid_, sig);
    while (std::chrono::steady_clock::now() - t0 < timeout) {
      if (waitpid(pid_, &status_, WNOHANG) == pid_) {
        exited_ = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    const auto ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0);
    if (!exited_) return {-1000, ms};
    return {WIFEXITED(status_) ? WEXITSTATUS(status_) : -WTERMSIG(status_), ms};
  }

  // Runs naneyed to completion (for --check-config); returns the exit code.
  int wait_exit(std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
    const auto t0 = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - t0 < timeout) {
      if (waitpid(pid_, &status_, WNOHANG) == pid_) {
        exited_ = true;
        return WIFEXITED(status_) ? WEXITSTATUS(status_) : -WTERMSIG(status_);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1000;
  }

  void signal(int sig) { kill(pid_, sig); }
  std::string log() const { return read_file(log_); }
  std::string out() const { return read_file(log_.string() + ".out"); }
  bool running() const { return pid_ > 0 && !exited_; }
  pid_t pid() const { return pid_; }

 private:
  std::filesystem::path log_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool exited_ = false;
};

}  // namespace naneye::daemon::test
