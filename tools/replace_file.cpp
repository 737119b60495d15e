#include "replace_file.hpp"

#include <string>

namespace naneye::tools {

void replace_file(const std::filesystem::path& out,
                  const std::function<void(const std::filesystem::path&)>& write,
                  std::string_view temp_extension) {
  const std::string name =
      temp_extension.empty() ? out.filename().string() : out.stem().string() + std::string(temp_extension);
  const std::filesystem::path tmp = out.parent_path() / (".part-" + name);
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
