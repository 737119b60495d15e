#include "naneye/driver/image_source.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "log.hpp"
#include "naneye/base/clock.hpp"
#include "naneye/driver/replay_clock.hpp"

namespace naneye::driver {
namespace {

// The timeline's spacing when the replay is not paced (fps=0): the sensors' nominal 50 fps, so that
// the timestamps look like a camera's and the pairer's tolerance means what it does for one.
constexpr double kUnpacedFps = 50.0;
// Highest pacing accepted: far above the sensors' 62 fps, and low enough that a pair is >= 1 ms.
constexpr double kMaxFps = 1000.0;

[[noreturn]] void bad(const std::string& name, const std::string& value, const char* accepted) {
  throw SourceError("images://: parameter '" + name + "' has a bad value '" + value +
                    "'; accepted: " + accepted);
}

bool starts_with_nocase(const std::string& s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(s[i])) != prefix[i]) return false;
  return true;
}

SourceInfo images_info(const ImagesUri& o, std::string uri) {
  SourceInfo i;
  i.uri = uri.empty() ? "images://" + o.dir : std::move(uri);
  i.kind = "images";
  i.device = o.dir.empty() ? std::to_string(o.pairs.size()) + " listed pairs" : o.dir;
  i.live = o.fps > 0;
  i.nominal_fps = o.fps;
  return i;
}

}  // namespace

ImagesUri parse_images_uri(const SourceUri& uri) {
  ImagesUri o;
  o.dir = uri.target;
  // Images have no reference pixels: checking them would test the picture, not the transfer.
  StreamSettings defaults;
  defaults.parser.reference.enabled = false;
  std::vector<std::string> lefts, rights;
  for (const auto& [name, value] : uri.params) {
    if (name == "left" || name == "right") {
      if (value.empty()) bad(name, value, "an image file path");
      (name == "left" ? lefts : rights).push_back(value);
    } else if (name == "fps") {
      double f = 0;
      const auto [p, ec] = std::from_chars(value.data(), value.data() + value.size(), f);
      if (value.empty() || ec != std::errc() || p != value.data() + value.size() || !std::isfinite(f) ||
          f < 0 || f > kMaxFps)
        bad(name, value, "pairs per second, 0 (as fast as taken) to 1000");
      o.fps = f;
    } else if (name == "loop") {
      if (value != "0" && value != "1") bad(name, value, "0 or 1");
      o.loop = value == "1";
    } else if (name == "bits") {
      if (value != "16" && value != "10") bad(name, value, "16 (full-scale 16-bit files) or 10");
      o.image.bits16 = value == "10" ? 10 : 16;
    } else if (std::find(kStreamParams.begin(), kStreamParams.end(), name) == kStreamParams.end()) {
      throw SourceError("images://: unknown parameter '" + name +
                        "'; accepted: left, right, fps, loop, bits, color, tolerance_ms, reference");
    }
  }
  o.stream = parse_stream_params(uri, defaults);
  o.image.color = o.stream.parser.color;
  if (lefts.size() != rights.size())
    throw SourceError("images://: " + std::to_string(lefts.size()) + " left= but " +
                      std::to_string(rights.size()) + " right= files: give them in pairs");
  for (std::size_t i = 0; i < lefts.size(); ++i) o.pairs.emplace_back(lefts[i], rights[i]);
  if (o.dir.empty() == o.pairs.empty())
    throw SourceError("images://: give a folder (images:///path/dir) or left= and right= files, not " +
                      std::string(o.dir.empty() ? "neither" : "both"));
  return o;
}

ImagePairList list_image_pairs(const ImagesUri& uri) {
  ImagePairList out;
  if (!uri.pairs.empty()) {
    out.pairs = uri.pairs;
    return out;
  }
  std::vector<std::string> lefts, rights;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(uri.dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!is_image_file_name(name)) continue;
    if (starts_with_nocase(name, "left")) lefts.push_back(it->path().string());
    if (starts_with_nocase(name, "right")) rights.push_back(it->path().string());
  }
  if (ec) throw SourceError("images://" + uri.dir + ": cannot list the folder: " + ec.message());
  std::sort(lefts.begin(), lefts.end());
  std::sort(rights.begin(), rights.end());
  const std::size_t n = std::min(lefts.size(), rights.size());
  for (std::size_t i = 0; i < n; ++i) out.pairs.emplace_back(lefts[i], rights[i]);
  for (std::size_t i = n; i < lefts.size(); ++i) out.unmatched.push_back(lefts[i]);
  for (std::size_t i = n; i < rights.size(); ++i) out.unmatched.push_back(rights[i]);
  if (out.pairs.empty())
    throw SourceError("images://" + uri.dir + ": no stereo pair: " + std::to_string(lefts.size()) +
                      " left* and " + std::to_string(rights.size()) +
                      " right* image files (.png .jpg .pgm .bmp .tif ...)");
  return out;
}

ImageSource::ImageSource(ImagesUri options, std::string uri_text)
    : ByteStreamSource(images_info(options, std::move(uri_text)), options.stream),
      options_(std::move(options)) {}

ImageSource::~ImageSource() {
  stop();
}

void ImageSource::open() {
  list_ = list_image_pairs(options_);
  for (const auto& f : list_.unmatched) log()->warn("images: {} has no partner, skipped", f);
}

bool ImageSource::play_pass(std::vector<std::uint8_t>& record) {
  Image10 image;
  std::array<std::vector<std::uint16_t>, 2> eyes;  // swapped with image.pixels: buffers are reused
  std::size_t fed = 0, skipped = 0;
  std::string last_error;
  ReplayClock pace;  // the fps's spacing; a held pass goes on from its late pair
  const std::uint64_t first = pair_clock_;
  for (const auto& [left, right] : list_.pairs) {
    if (stopping()) return false;
    // Decode both before feeding either, so a bad file skips the whole pair (never half of one).
    try {
      for (int eye = 0; eye < 2; ++eye) {
        read_image(eye == 0 ? left : right, options_.image, image);
        if (image.width != kSensorSize || image.height != kSensorSize)
          throw ImageError((eye == 0 ? left : right) + ": " + std::to_string(image.width) + " x " +
                           std::to_string(image.height) + " pixels; a frame is 250 x 250 (naneye recon " +
                           "--left/--right reads other sizes)");
        eyes[eye].swap(image.pixels);
      }
    } catch (const ImageError& e) {
      ++skipped;
      last_error = e.what();
      AtomicCounters::add(live_counters().transfer_errors);
      log()->warn("images: pair skipped: {}", e.what());
      continue;
    }
    if (options_.fps > 0 &&
        !sleep_until(
            pace.due(static_cast<std::int64_t>(static_cast<double>(pair_clock_ - first) * 1e9 / options_.fps),
                     std::chrono::steady_clock::now())))
      return false;
    const double tick_fps = options_.fps > 0 ? options_.fps : kUnpacedFps;
    const auto ticks = static_cast<std::uint32_t>(
        static_cast<std::uint64_t>(static_cast<double>(pair_clock_) * kTickHz / tick_fps) & 0xffffffffu);
    for (int eye = 0; eye < 2; ++eye) {
      const RecordHeader h{seq_++, eye == 0 ? Sensor::left : Sensor::right, ticks};
      encode_record(h, std::span<const std::uint16_t, kPixelCount>(eyes[eye].data(), kPixelCount),
                    std::span<std::uint8_t, kRecordSize>(record.data(), kRecordSize));
      feed(record, base::monotonic_ns());
    }
    ++pair_clock_;
    ++fed;
  }
  if (skipped)
    set_error("images: " + std::to_string(skipped) + " of " + std::to_string(list_.pairs.size()) +
              " pairs skipped; last: " + last_error);
  if (fed == 0) {
    fail("images: none of the " + std::to_string(list_.pairs.size()) +
         " pairs could be read; last: " + last_error);
    return false;
  }
  return true;
}

void ImageSource::run() {
  std::vector<std::uint8_t> record(kRecordSize);
  log()->info("images: {} pairs{}{}", list_.pairs.size(),
              options_.fps > 0 ? fmt::format(" at {} fps", options_.fps) : std::string(" as fast as taken"),
              options_.loop ? ", looping" : "");
  do {
    if (!play_pass(record)) return;
  } while (options_.loop && !stopping());
  end_of_stream(base::monotonic_ns());
}

void register_image_source(SourceRegistry& registry) {
  registry.add("images", [](const SourceUri& uri) -> std::unique_ptr<FrameSource> {
    return std::make_unique<ImageSource>(parse_images_uri(uri), uri.text);
  });
}

}  // namespace naneye::driver
