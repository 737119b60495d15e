// One libFuzzer target per entry (clang, -DNANEYE_FUZZ=ON): NANEYE_FUZZ_ENTRY names the function
// of fuzz_entries.hpp this binary fuzzes.
#include "fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return naneye::fuzz::NANEYE_FUZZ_ENTRY(data, size);
}
