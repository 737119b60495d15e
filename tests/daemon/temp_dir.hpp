#pragma once
// A folder under the system temp dir, removed at the end of the test.
#include <cstdlib>
#include <filesystem>
#include <string>

namespace naneye::daemon::test {

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "naneyed-test-XXXXXX").string();
    path = mkdtemp(tmpl.data());
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

}  // namespace naneye::daemon::test
