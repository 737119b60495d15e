#pragma once
// The CLI's output files (a calibration, a fixed pattern) replace their target whole or not at all.
#include <filesystem>
#include <functional>
#include <string_view>

namespace naneye::tools {

// Calls write(tmp) for a temporary beside `out` and renames it over `out` once written: a failed
// write leaves neither half a file nor the temporary, and rethrows. The temporary is ".part-" + out's
// name, its endings kept (cv::FileStorage picks YAML, XML, JSON and gzip from them), or with
// `temp_extension` in place of out's last one (a writer that needs one format whatever `out` says).
void replace_file(const std::filesystem::path& out,
                  const std::function<void(const std::filesystem::path&)>& write,
                  std::string_view temp_extension = {});

}  // namespace naneye::tools
