// The .neyd container: bit-exact round trip and damage reported with its place.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "naneye/driver/neyd.hpp"
#include "temp_file.hpp"

namespace naneye::driver {
namespace {

struct Chunk {
  std::vector<std::uint8_t> bytes;
  std::int64_t t;
};

std::vector<Chunk> random_chunks(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Chunk> v;
  for (int i = 0; i < n; ++i) {
    Chunk c;
    c.bytes.resize(rng() % 20000);
    for (auto& b : c.bytes) b = static_cast<std::uint8_t>(rng());
    c.t = 1'000'000'000 + i * 333'333 + static_cast<std::int64_t>(rng() % 1000);
    v.push_back(std::move(c));
  }
  return v;
}

void write_file(const std::string& path, const std::vector<Chunk>& chunks, bool close = true) {
  NeydHeader h;
  h.usb_vid = 0x10f8;
  h.usb_pid = 0xc487;
  h.start_wall_ns = 1'700'000'000'123'456'789;
  h.start_monotonic_ns = 42;
  h.note = R"({"uri":"usb://10f8:c487"})";
  NeydWriter w(path, h);
  for (const auto& c : chunks) w.write_chunk(c.bytes, c.t);
  if (close) w.close();
}

// Reads every chunk; returns how many came out before the end or an error (put in `error`).
std::size_t read_all(const std::string& path, const std::vector<Chunk>& want, std::string& error) {
  NeydReader r(path);
  std::vector<std::uint8_t> data;
  std::int64_t t = 0;
  std::size_t n = 0;
  try {
    while (r.next(data, t)) {
      EXPECT_EQ(data, want[n].bytes) << "chunk " << n;
      EXPECT_EQ(t, want[n].t);
      ++n;
    }
  } catch (const NeydError& e) {
    error = e.what();
  }
  return n;
}

TEST(Neyd, RoundTripIsBitExact) {
  test::TempFile f("roundtrip.neyd");
  const auto chunks = random_chunks(40, 1);
  write_file(f.str(), chunks);
  EXPECT_TRUE(NeydReader::is_neyd(f.str()));
  NeydReader r(f.str());
  EXPECT_EQ(r.header().usb_vid, 0x10f8);
  EXPECT_EQ(r.header().usb_pid, 0xc487);
  EXPECT_EQ(r.header().start_wall_ns, 1'700'000'000'123'456'789);
  EXPECT_EQ(r.header().start_monotonic_ns, 42);
  EXPECT_EQ(r.header().note, R"({"uri":"usb://10f8:c487"})");
  std::string error;
  EXPECT_EQ(read_all(f.str(), chunks, error), 40u);
  EXPECT_EQ(error, "");
}

TEST(Neyd, TruncatedChunkSaysWhereAfterTheEarlierChunks) {
  test::TempFile f("truncated.neyd");
  const auto chunks = random_chunks(10, 2);
  write_file(f.str(), chunks);
  auto bytes = f.read();
  // Offset of chunk 6: header (36 + note + 4) then 20 + length per chunk.
  std::size_t at = 36 + 25 + 4;
  for (int i = 0; i < 6; ++i) at += 20 + chunks[i].bytes.size();
  bytes.resize(at + 20 + chunks[6].bytes.size() / 2);
  f.write(bytes);
  std::string error;
  EXPECT_EQ(read_all(f.str(), chunks, error), 6u);
  EXPECT_NE(error.find("byte offset " + std::to_string(at)), std::string::npos) << error;
  EXPECT_NE(error.find("chunk 6"), std::string::npos) << error;
  EXPECT_NE(error.find("truncated chunk"), std::string::npos) << error;
}

TEST(Neyd, CrcMismatchSaysWhere) {
  test::TempFile f("crc.neyd");
  auto chunks = random_chunks(5, 3);
  chunks[3].bytes.resize(100);
  write_file(f.str(), chunks);
  auto bytes = f.read();
  std::size_t at = 36 + 25 + 4;
  for (int i = 0; i < 3; ++i) at += 20 + chunks[i].bytes.size();
  bytes[at + 20 + 50] ^= 0x10;
  f.write(bytes);
  std::string error;
  EXPECT_EQ(read_all(f.str(), chunks, error), 3u);
  EXPECT_NE(error.find("CRC mismatch"), std::string::npos) << error;
  EXPECT_NE(error.find("byte offset " + std::to_string(at)), std::string::npos) << error;
  EXPECT_NE(error.find("chunk 3"), std::string::npos) << error;
}

TEST(Neyd, MissingEndMarkerIsReportedAsTruncation) {
  test::TempFile f("noend.neyd");
  const auto chunks = random_chunks(4, 4);
  write_file(f.str(), chunks);
  auto bytes = f.read();
  bytes.resize(bytes.size() - 24);
  f.write(bytes);
  std::string error;
  EXPECT_EQ(read_all(f.str(), chunks, error), 4u);
  EXPECT_NE(error.find("without the end marker"), std::string::npos) << error;
}

TEST(Neyd, ADamagedLengthCostsWhatTheFileHoldsNotWhatItClaims) {
  // The last chunk's length field says 60 MiB (under the 64 MiB limit, so it is read); the file
  // holds 300 bytes of it. Refused as truncated, and the buffer grew with the bytes that arrived,
  // not to the claim (before: 60 MiB allocated to find 300 bytes).
  test::TempFile f("claim.neyd");
  auto chunks = random_chunks(2, 5);
  chunks[1].bytes.resize(300);
  write_file(f.str(), chunks, false);
  auto bytes = f.read();
  const std::size_t at = 36 + 25 + 4 + 20 + chunks[0].bytes.size();
  constexpr std::uint32_t kClaim = 60u << 20;
  for (int i = 0; i < 4; ++i) bytes[at + 4 + i] = static_cast<std::uint8_t>(kClaim >> (8 * i));
  f.write(bytes);
  NeydReader r(f.str());
  std::vector<std::uint8_t> data;
  std::int64_t t = 0;
  ASSERT_TRUE(r.next(data, t));
  try {
    r.next(data, t);
    ADD_FAILURE() << "a chunk with 300 of 60 MiB present was accepted";
  } catch (const NeydError& e) {
    EXPECT_NE(std::string(e.what()).find("300 of 62914560 payload bytes"), std::string::npos) << e.what();
  }
  EXPECT_LE(data.capacity(), std::size_t{2} << 20);
}

TEST(Neyd, BadMagicAndBadHeaderAreRefused) {
  std::istringstream junk(std::string("RIFF0000WAVEfmt 0123456789012345678901234567890"));
  EXPECT_THROW(NeydReader r(junk), NeydError);
  test::TempFile f("header.neyd");
  write_file(f.str(), {});
  auto bytes = f.read();
  bytes[20] ^= 1;  // inside the wall-clock time: header CRC
  std::istringstream damaged(std::string(bytes.begin(), bytes.end()));
  try {
    NeydReader r(damaged);
    ADD_FAILURE() << "accepted a damaged header";
  } catch (const NeydError& e) {
    EXPECT_NE(std::string(e.what()).find("header CRC"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace naneye::driver
