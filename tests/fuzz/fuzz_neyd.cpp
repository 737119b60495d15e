// libFuzzer target: the .neyd reader feeding the parser (clang, -DNANEYE_FUZZ=ON).
#include "fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return naneye::fuzz::read_neyd(data, size);
}
