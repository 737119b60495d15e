#pragma once
// The fuzzed entry points, shared by the libFuzzer targets (clang, -DNANEYE_FUZZ=ON) and by the
// corpus replay test that every build runs. Each aborts on a broken invariant.
#include <cstddef>
#include <cstdint>

namespace naneye::fuzz {

// data[0]: chunking, data[1]: sensor size and parser options, the rest: the byte stream.
int parse_stream(const std::uint8_t* data, std::size_t size);
// data: a whole .neyd file; its chunks go through the parser (4 x 4 sensor records).
int read_neyd(const std::uint8_t* data, std::size_t size);

}  // namespace naneye::fuzz
