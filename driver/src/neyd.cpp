#include "naneye/driver/neyd.hpp"

#include <zlib.h>

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <fstream>

namespace naneye::driver {
namespace {

// "NEYD" then CR LF SUB LF: like PNG's magic, it shows text-mode mangling of the file at once.
constexpr std::array<std::uint8_t, 8> kMagic = {'N', 'E', 'Y', 'D', 0x0D, 0x0A, 0x1A, 0x0A};
constexpr std::uint32_t kChunkTag = 0x4B4E4843;  // "CHNK"
constexpr std::uint32_t kEndTag = 0x21444E45;    // "END!"
constexpr std::size_t kFixedHeader = 36;         // magic .. note length
constexpr std::size_t kChunkHeader = 20;         // tag, length, time, crc
constexpr std::size_t kEndSize = 24;             // tag, reserved, chunk count, payload bytes

template <class T>
void put_le(std::uint8_t* p, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i)
    p[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i));
}
template <class T>
T get_le(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return static_cast<T>(v);
}

std::uint32_t crc(std::span<const std::uint8_t> b, std::uint32_t start = 0) {
  uLong c = start;
  while (!b.empty()) {  // zlib takes uInt lengths
    const auto n = static_cast<uInt>(std::min<std::size_t>(b.size(), 1u << 30));
    c = crc32(c, b.data(), n);
    b = b.subspan(n);
  }
  return static_cast<std::uint32_t>(c);
}

}  // namespace

NeydWriter::NeydWriter(const std::string& path, const NeydHeader& h) : path_(path) {
  if (h.note.size() > kNeydMaxNote) throw SourceError(path + ": .neyd note longer than 1 MiB");
  // 0640: a capture shows what the camera saw; the owner and its group (naneye) read it, others not.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) throw SourceError(path + ": cannot create: " + std::strerror(errno));
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    ::close(fd);
    throw SourceError(path + ": cannot create: " + std::strerror(errno));
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  std::vector<std::uint8_t> b(kFixedHeader + h.note.size() + 4);
  std::memcpy(b.data(), kMagic.data(), kMagic.size());
  put_le<std::uint16_t>(&b[8], kNeydVersion);
  put_le<std::uint16_t>(&b[10], 0);  // flags, none defined
  put_le<std::uint16_t>(&b[12], h.usb_vid);
  put_le<std::uint16_t>(&b[14], h.usb_pid);
  put_le<std::int64_t>(&b[16], h.start_wall_ns);
  put_le<std::int64_t>(&b[24], h.start_monotonic_ns);
  put_le<std::uint32_t>(&b[32], static_cast<std::uint32_t>(h.note.size()));
  std::memcpy(&b[kFixedHeader], h.note.data(), h.note.size());
  const std::size_t n = kFixedHeader + h.note.size();
  put_le<std::uint32_t>(&b[n], crc(std::span(b).first(n)));
  put(b.data(), b.size());
}

NeydWriter::~NeydWriter() {
  if (file_) std::fclose(file_);
}

void NeydWriter::fail(int err) {
  // The first error is the one to report; later ones follow from it. (The capture thread writes,
  // the recorder's thread flushes: either may fail first.)
  std::lock_guard lock(error_mu_);
  if (failed_.load(std::memory_order_acquire)) return;
  error_ = path_ + ": write failed: " + std::strerror(err);
  failed_.store(true, std::memory_order_release);
}

void NeydWriter::put(const void* data, std::size_t n) {
  if (n && !failed_.load(std::memory_order_acquire) && std::fwrite(data, 1, n, file_) != n) fail(errno);
}

void NeydWriter::write_chunk(std::span<const std::uint8_t> bytes, std::int64_t host_ns) {
  if (!file_) throw SourceError(path_ + ": write after close");
  // After a failure nothing more is written: the file ends at the last chunk that was (at most one
  // chunk is cut, and a reader replays every chunk before it).
  if (failed_.load(std::memory_order_acquire)) return;
  std::uint8_t h[kChunkHeader];
  put_le<std::uint32_t>(h, kChunkTag);
  put_le<std::uint32_t>(h + 4, static_cast<std::uint32_t>(bytes.size()));
  put_le<std::int64_t>(h + 8, host_ns);
  put_le<std::uint32_t>(h + 16, crc(bytes));
  // One locked write: the recorder's flush() from its own thread never lands inside a chunk. (stdio
  // writes its buffer out by itself when it fills, which may still cut one chunk; a reader then
  // reports the file truncated after the whole chunks before it.) A std::mutex, not flockfile():
  // ThreadSanitizer does not see the ordering flockfile() gives, and would report the counters.
  std::lock_guard lock(io_mu_);
  put(h, sizeof h);
  put(bytes.data(), bytes.size());
  if (!failed_.load(std::memory_order_acquire)) {
    ++chunks_;
    bytes_ += bytes.size();
  }
}

void NeydWriter::flush() {
  if (!file_ || failed_.load(std::memory_order_acquire)) return;
  std::lock_guard lock(io_mu_);
  if (std::fflush(file_) != 0) {
    fail(errno);
  } else {
    flushed_chunks_ = chunks_;
    flushed_bytes_ = bytes_;
  }
}

std::uint64_t NeydWriter::chunks() const {
  // After a failure only what a flush saw through is sure to be in the file.
  std::lock_guard lock(io_mu_);
  return failed_.load(std::memory_order_acquire) ? flushed_chunks_ : chunks_;
}

std::uint64_t NeydWriter::payload_bytes() const {
  std::lock_guard lock(io_mu_);
  return failed_.load(std::memory_order_acquire) ? flushed_bytes_ : bytes_;
}

std::optional<std::string> NeydWriter::error() const {
  std::lock_guard lock(error_mu_);
  if (!failed_.load(std::memory_order_acquire)) return std::nullopt;
  return error_;
}

void NeydWriter::close() {
  if (!file_) return;
  // No end marker after a failure: the file then reads as truncated after its last whole chunk,
  // which is what it is.
  if (!failed_.load(std::memory_order_acquire)) {
    {
      std::lock_guard lock(io_mu_);
      std::uint8_t e[kEndSize];
      put_le<std::uint32_t>(e, kEndTag);
      put_le<std::uint32_t>(e + 4, 0);
      put_le<std::uint64_t>(e + 8, chunks_);
      put_le<std::uint64_t>(e + 16, bytes_);
      put(e, sizeof e);
    }
    flush();
  }
  if (std::fclose(file_) != 0) fail(errno);
  file_ = nullptr;
  if (auto e = error()) throw SourceError(*e);
}

bool NeydReader::is_neyd(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::array<char, 8> m{};
  return f.read(m.data(), m.size()) && std::memcmp(m.data(), kMagic.data(), m.size()) == 0;
}

NeydReader::NeydReader(const std::string& path) : name_(path) {
  auto f = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*f) throw SourceError(path + ": cannot open: " + std::strerror(errno));
  owned_ = std::move(f);
  in_ = owned_.get();
  read_header();
}

NeydReader::NeydReader(std::istream& in) : in_(&in), name_(".neyd stream") {
  read_header();
}

void NeydReader::fail(const std::string& what, std::uint64_t at) const {
  throw NeydError(name_ + ": damaged .neyd at byte offset " + std::to_string(at) + " (chunk " +
                      std::to_string(chunk_) + "): " + what,
                  at, chunk_);
}

std::size_t NeydReader::read(void* out, std::size_t n) {
  in_->read(static_cast<char*>(out), static_cast<std::streamsize>(n));
  const auto got = static_cast<std::size_t>(in_->gcount());
  offset_ += got;
  return got;
}

void NeydReader::read_header() {
  std::uint8_t b[kFixedHeader];
  const std::size_t got = read(b, sizeof b);
  if (got < kMagic.size() || std::memcmp(b, kMagic.data(), kMagic.size()) != 0)
    throw NeydError(name_ + ": not a .neyd file (bad magic at byte offset 0)", 0, 0);
  if (got < sizeof b) fail("truncated header: " + std::to_string(got) + " of 36 bytes", got);
  header_.version = get_le<std::uint16_t>(b + 8);
  if (header_.version != kNeydVersion)
    fail("unsupported version " + std::to_string(header_.version) + " (this reader knows version 1)", 8);
  header_.usb_vid = get_le<std::uint16_t>(b + 12);
  header_.usb_pid = get_le<std::uint16_t>(b + 14);
  header_.start_wall_ns = get_le<std::int64_t>(b + 16);
  header_.start_monotonic_ns = get_le<std::int64_t>(b + 24);
  const auto note_len = get_le<std::uint32_t>(b + 32);
  if (note_len > kNeydMaxNote) fail("header note length " + std::to_string(note_len) + " exceeds 1 MiB", 32);
  header_.note.resize(note_len);
  if (read(header_.note.data(), note_len) < note_len) fail("truncated header note", offset_);
  std::uint8_t c[4];
  if (read(c, 4) < 4) fail("truncated header CRC", offset_);
  std::uint32_t want = crc(std::span<const std::uint8_t>(b, sizeof b));
  want = crc(std::span(reinterpret_cast<const std::uint8_t*>(header_.note.data()), note_len), want);
  if (get_le<std::uint32_t>(c) != want) fail("header CRC mismatch", offset_ - 4);
}

bool NeydReader::next(std::vector<std::uint8_t>& data, std::int64_t& host_ns) {
  if (ended_) return false;
  const std::uint64_t at = offset_;
  std::uint8_t h[kChunkHeader];
  const std::size_t got = read(h, 4);
  if (got == 0)
    fail("file ends without the end marker after " + std::to_string(chunk_) +
             " chunks (recording interrupted?)",
         at);
  if (got < 4) fail("truncated chunk header", at);
  const auto tag = get_le<std::uint32_t>(h);
  if (tag == kEndTag) {
    std::uint8_t e[kEndSize - 4];
    if (read(e, sizeof e) < sizeof e) fail("truncated end marker", at);
    const auto chunks = get_le<std::uint64_t>(e + 4);
    const auto bytes = get_le<std::uint64_t>(e + 12);
    if (chunks != chunk_ || bytes != payload_)
      fail("end marker counts " + std::to_string(chunks) + " chunks / " + std::to_string(bytes) +
               " bytes, file holds " + std::to_string(chunk_) + " / " + std::to_string(payload_),
           at);
    ended_ = true;
    return false;
  }
  if (tag != kChunkTag) fail("bad chunk tag (expected \"CHNK\" or \"END!\")", at);
  if (read(h + 4, kChunkHeader - 4) < kChunkHeader - 4) fail("truncated chunk header", at);
  const auto len = get_le<std::uint32_t>(h + 4);
  if (len > kNeydMaxChunk) fail("chunk length " + std::to_string(len) + " exceeds 64 MiB", at + 4);
  host_ns = get_le<std::int64_t>(h + 8);
  // A damaged length must not cost its claim in memory: past the capacity already held, the buffer
  // grows with the bytes that arrive, kGrowStep at a time (a 100-byte file claiming 64 MiB would
  // otherwise allocate 64 MiB before it is found truncated).
  std::size_t payload = 0;
  if (len <= data.capacity()) {
    data.resize(len);
    payload = read(data.data(), len);
  } else {
    constexpr std::size_t kGrowStep = 1u << 20;
    while (payload < len) {
      const std::size_t step = std::min<std::size_t>(len - payload, kGrowStep);
      data.resize(payload + step);
      const std::size_t got = read(data.data() + payload, step);
      payload += got;
      if (got < step) break;
    }
  }
  if (payload < len)
    fail("truncated chunk: " + std::to_string(payload) + " of " + std::to_string(len) +
             " payload bytes present",
         at);
  if (crc(data) != get_le<std::uint32_t>(h + 16))
    fail("chunk CRC mismatch (" + std::to_string(len) + " bytes)", at);
  ++chunk_;
  payload_ += len;
  return true;
}

}  // namespace naneye::driver
