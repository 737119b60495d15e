#pragma once
// file://: replays a .raw dump (the spec's byte stream, fed in transfer-sized pieces) or a .neyd
// capture (its chunks as recorded) through the parser live capture runs.
//   speed=realtime  follows the recorded timing (.neyd chunk times; .raw record timestamps), and
//                   hands over like a live source (drop-oldest); a replay thread held by the machine
//                   goes on at the recorded spacing instead of catching up (ReplayClock);
//   speed=<factor>  the same, time divided by the factor;
//   speed=max       as fast as the consumer takes pairs, never dropping one (blocking hand-over).
//   loop=1          starts over at the end, forever (the timeline keeps going forward).
// A damaged .neyd ends the replay in state failed, error() saying where, after every complete frame
// before the damage was delivered; a .raw simply ends (a cut last record is counted).
#include <string>

#include "naneye/driver/byte_stream_source.hpp"
#include "naneye/driver/replay_clock.hpp"
#include "naneye/driver/source_uri.hpp"

namespace naneye::driver {

class FileSource : public ByteStreamSource {
 public:
  explicit FileSource(FileUri options, std::string uri_text = {});
  ~FileSource() override;
  bool is_neyd() const { return neyd_; }

 protected:
  void open() override;
  void run() override;
  void on_record_start(std::int64_t sensor_ns) override;

 private:
  bool play_raw();                      // one pass; false when stopped
  bool play_neyd();                     // one pass; false when stopped; throws NeydError on damage
  bool pace(std::int64_t recorded_ns);  // waits until recorded time (from the pass start) is due

  FileUri options_;
  bool neyd_ = false;
  ReplayClock clock_;
  std::uint64_t resyncs_logged_ = 0;
};

}  // namespace naneye::driver
