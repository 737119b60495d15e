#pragma once
// images://: stereo pairs from image files saved by other software, through the same byte-stream
// path as a camera (each image is encoded as a record, so parser, pairer, pool, ring, counters and
// `naneye record` behave as with a device).
//   images:///path/dir          the folder's left* and right* image files, each sorted by name,
//                               paired in order (extras without a partner are skipped, with a warning)
//   images://?left=L1&right=R1&left=L2&right=R2   an explicit list, paired in the order given
//     &fps=<f>      paced at f pairs per second with a live (drop-oldest) hand-over; 0 (default):
//                   as fast as the consumer takes pairs, never dropping one
//     &loop=0|1     start over at the end
//     &bits=16|10   16-bit files: full scale (default) or the sensor's own 10-bit values
//   plus the stream parameters (color=mono|grbg, tolerance_ms; reference defaults to off: an image
//   carries no reference pixels).
// A frame is 250 x 250 (driver::Frame): an image of another size is refused with its size (use
// `naneye recon --left/--right` for other cameras). An unreadable or refused pair is skipped, logged,
// counted in transfer_errors and named in error(); the replay goes on with the others, and fails
// only when a whole pass delivered nothing.
#include <string>
#include <utility>
#include <vector>

#include "naneye/driver/byte_stream_source.hpp"
#include "naneye/driver/image_file.hpp"
#include "naneye/driver/source_registry.hpp"
#include "naneye/driver/source_uri.hpp"

namespace naneye::driver {

struct ImagesUri {
  std::string dir;                                         // images:///dir, or empty with a list
  std::vector<std::pair<std::string, std::string>> pairs;  // the explicit list (left, right)
  double fps = 0;
  bool loop = false;
  ImageSettings image;
  StreamSettings stream;
};
// Pure: no file is touched (list_image_pairs does that). Throws SourceError naming the parameter.
ImagesUri parse_images_uri(const SourceUri& uri);

struct ImagePairList {
  std::vector<std::pair<std::string, std::string>> pairs;
  std::vector<std::string> unmatched;  // files of the folder that found no partner
};
// The pairs a URI names: its list, or its folder's left*/right* images. Throws SourceError when the
// folder cannot be read or there is no pair at all.
ImagePairList list_image_pairs(const ImagesUri& uri);

class ImageSource : public ByteStreamSource {
 public:
  explicit ImageSource(ImagesUri options, std::string uri_text = {});
  ~ImageSource() override;

 protected:
  void open() override;
  void run() override;

 private:
  bool play_pass(std::vector<std::uint8_t>& record);  // false when stopped or nothing was readable

  ImagesUri options_;
  ImagePairList list_;
  std::uint64_t pair_clock_ = 0;  // pairs fed so far, all passes: the synthetic timeline
  std::uint8_t seq_ = 0;
};

void register_image_source(SourceRegistry& registry);

}  // namespace naneye::driver
