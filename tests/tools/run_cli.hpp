#pragma once
// Runs the real `naneye` binary the way a user would and captures what it prints.
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace naneye::test {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout; stderr is merged in when merge_stderr is set
};

inline CliResult run_cli(const std::string& args, bool merge_stderr = false) {
  const std::string cmd = std::string(NANEYE_CLI) + " " + args + (merge_stderr ? " 2>&1" : " 2>/dev/null");
  CliResult r;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = ::pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace naneye::test
