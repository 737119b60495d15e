#include "naneye/driver/file_source.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

#include "log.hpp"
#include "naneye/base/clock.hpp"
#include "naneye/driver/neyd.hpp"
#include "naneye/driver/source_registry.hpp"

namespace naneye::driver {
namespace {

SourceInfo file_info(const FileUri& o, std::string uri) {
  SourceInfo i;
  i.uri = uri.empty() ? "file://" + o.path : std::move(uri);
  i.kind = "file";
  i.device = o.path;
  i.live = o.speed != FileUri::Speed::max;
  return i;
}

}  // namespace

FileSource::FileSource(FileUri options, std::string uri_text)
    : ByteStreamSource(file_info(options, std::move(uri_text)), options.stream),
      options_(std::move(options)),
      clock_(options_.speed == FileUri::Speed::factor ? options_.factor : 1.0) {}

FileSource::~FileSource() {
  stop();
}

void FileSource::open() {
  std::ifstream f(options_.path, std::ios::binary);
  if (!f) throw SourceError(options_.path + ": cannot open: " + std::strerror(errno));
  neyd_ = NeydReader::is_neyd(options_.path);
  if (neyd_) NeydReader check(options_.path);  // a bad header fails start() itself
}

bool FileSource::pace(std::int64_t recorded_ns) {
  if (options_.speed == FileUri::Speed::max) return !stopping();
  const auto due = clock_.due(recorded_ns, std::chrono::steady_clock::now());
  if (clock_.resyncs() != resyncs_logged_) {
    if (resyncs_logged_ == 0)
      log()->info(
          "{}: the replay was held more than {} ms; it goes on from the late record at the "
          "recorded spacing (said once)",
          info().uri, ReplayClock::kHeldAfter.count());
    resyncs_logged_ = clock_.resyncs();
  }
  return sleep_until(due);
}

bool FileSource::play_raw() {
  std::ifstream f(options_.path, std::ios::binary);
  if (!f) throw SourceError(options_.path + ": cannot open: " + std::strerror(errno));
  std::vector<std::uint8_t> buf(options_.chunk_bytes);
  while (!stopping()) {
    f.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
    const auto n = static_cast<std::size_t>(f.gcount());
    if (n == 0) break;
    feed(std::span(buf).first(n), base::monotonic_ns());  // paced per record in on_record_start()
  }
  return !stopping();
}

bool FileSource::play_neyd() {
  NeydReader reader(options_.path);
  std::vector<std::uint8_t> data;
  std::int64_t t = 0;
  while (!stopping() && reader.next(data, t)) {
    if (!pace(t)) return false;
    feed(data, base::monotonic_ns());
  }
  return !stopping();
}

// .raw has no arrival times: each record is released when its own sensor timestamp is due.
void FileSource::on_record_start(std::int64_t sensor_ns) {
  if (!neyd_) pace(sensor_ns);
}

void FileSource::run() {
  for (;;) {
    clock_.restart();
    const std::uint64_t before = records_committed();
    try {
      if (!(neyd_ ? play_neyd() : play_raw())) return;
    } catch (const NeydError& e) {
      end_of_stream(base::monotonic_ns());
      log()->warn("{}", e.what());
      fail(e.what());
      return;
    }
    const bool again = options_.loop && records_committed() != before;  // an empty pass would spin
    end_of_stream(base::monotonic_ns(), again);
    if (!again) return;
  }
}

void register_file_source(SourceRegistry& registry) {
  registry.add("file", [](const SourceUri& uri) -> std::unique_ptr<FrameSource> {
    return std::make_unique<FileSource>(parse_file_uri(uri), uri.text);
  });
}

}  // namespace naneye::driver
