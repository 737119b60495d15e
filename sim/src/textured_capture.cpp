// Textured scenes written as a capture file (textured.hpp), for the CLI and the daemon.
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "naneye/sim/stream.hpp"
#include "naneye/sim/textured.hpp"

namespace naneye::sim {

std::vector<cv::Mat> write_textured_capture(const std::filesystem::path& raw_file, const TexturedRenderer& r,
                                            const std::vector<TexturedSceneSettings>& scenes,
                                            std::uint64_t seed) {
  Rng rng(seed);
  FrameClock clock(TimingSettings{}, rng() % (std::uint64_t{1} << 32), rng);
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(raw_file.c_str(), "wb"), &std::fclose);
  if (!f) throw std::runtime_error("sim: cannot write " + raw_file.string());
  ByteSink sink = [&](std::span<const std::uint8_t> b, std::int64_t) {
    if (std::fwrite(b.data(), 1, b.size(), f.get()) != b.size())
      throw std::runtime_error("sim: write error on " + raw_file.string());
  };
  RecordWriter out(sink, FaultSettings{}, seed, static_cast<std::uint8_t>(rng()));
  std::vector<cv::Mat> truth;
  for (const auto& s : scenes) {
    TexturedPair p = r.render(s, rng);
    const PairTime pt = clock.next(rng);
    auto span = [](const cv::Mat& m) {
      return std::span<const std::uint16_t, driver::kPixelCount>(m.ptr<std::uint16_t>(), driver::kPixelCount);
    };
    out.write(driver::Sensor::left, static_cast<std::uint32_t>(pt.left_ticks), span(p.left), 0);
    out.write(driver::Sensor::right, static_cast<std::uint32_t>(pt.right_ticks), span(p.right), 0);
    truth.push_back(p.depth);
  }
  out.finish();
  return truth;
}

}  // namespace naneye::sim
