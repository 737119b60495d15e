#include "replace_file.hpp"

namespace naneye::tools {

void replace_file(const std::filesystem::path& out,
                  const std::function<void(const std::filesystem::path&)>& write) {
  const std::filesystem::path tmp = out.parent_path() / (".part-" + out.filename().string());
  try {
    write(tmp);
    std::filesystem::rename(tmp, out);
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
}

}  // namespace naneye::tools
