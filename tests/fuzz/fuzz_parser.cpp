// libFuzzer target: the stream parser and pairer (clang, -DNANEYE_FUZZ=ON).
#include "fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return naneye::fuzz::parse_stream(data, size);
}
