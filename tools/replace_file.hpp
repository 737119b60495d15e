#pragma once
// The CLI's output files (a calibration, a fixed pattern) replace their target whole or not at all.
#include <filesystem>
#include <functional>

namespace naneye::tools {

// Calls write(tmp) for a temporary beside `out` (".part-" + its name: the endings stay, which
// cv::FileStorage picks YAML and gzip from) and renames it over `out` once written: a failed
// write leaves neither half a file nor the temporary, and rethrows.
void replace_file(const std::filesystem::path& out,
                  const std::function<void(const std::filesystem::path&)>& write);

}  // namespace naneye::tools
