#pragma once
// What kind of recording a path is, and a raw message source over the ROS 2
// storages: a single sqlite3 `.db3`, a single `.mcap`, or a ROS 2 bag folder
// (metadata.yaml + its files; several files = a split bag, merged by time).
// The kind is detected from the content, not from the extension. ROS1 bags
// are read through rosbag_storage by the sensor reader itself, pcap captures
// by the Ouster packet reader (formats/ouster.h, formats/pcap.h).
//
// Messages are opaque serialized payloads (CDR for ROS 2: formats/cdr.h).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"

namespace rvlio {

enum class RecordingKind {
  kRos1Bag,     // "#ROSBAG V2.0" magic
  kMcap,        // "\x89MCAP0\r\n" magic
  kSqlite3,     // "SQLite format 3\0" header
  kRos2Folder,  // a directory with metadata.yaml
  kPcap,        // a classic pcap capture (Ouster packets + metadata JSON, formats/ouster.h)
};
// "ros1", "mcap", "sqlite3", "ros2 folder", "pcap".
const char* RecordingKindName(RecordingKind kind);

// InvalidInput naming the path when it is missing, unreadable, an empty
// directory, a directory without metadata.yaml, or a file of none of the kinds
// (a `.bag` file of no known kind is reported as kRos1Bag: the ROS1 reader
// then says why it cannot read it).
StatusOr<RecordingKind> DetectRecording(const std::string& path);

struct RecordingTopic {
  std::string name;
  std::string type;                  // e.g. "sensor_msgs/msg/Imu"
  std::string serialization_format;  // "cdr"
};

struct RawMessage {
  int topic = -1;          // index into RecordingSource::topics()
  TimeNs stamp_ns = 0;     // the bag's receive (log) time
  std::vector<uint8_t> data;
};

// Per-topic counts and first/last receive times, for `rvlio info`.
struct RecordingTopicStats {
  int64_t count = 0;
  TimeNs first_ns = 0, last_ns = 0;
};

// Streams the messages of a ROS 2 recording in receive-time order (ties:
// storage order, then file order for a split bag), one at a time.
class RecordingSource {
 public:
  virtual ~RecordingSource() = default;
  // A .db3, a .mcap or a ROS 2 bag folder (not a ROS1 bag: InvalidInput).
  static StatusOr<std::unique_ptr<RecordingSource>> Open(const std::string& path);

  virtual const std::string& path() const = 0;
  virtual std::string storage() const = 0;  // "sqlite3" or "mcap"
  // Distinct MCAP chunk compressions ("none" for uncompressed chunks); empty
  // for sqlite3 or an unchunked MCAP.
  virtual std::vector<std::string> compressions() const = 0;
  virtual const std::vector<RecordingTopic>& topics() const = 0;
  // Restricts Next() to these topic indexes (all when never called); call
  // before the first Next().
  virtual Status SetTopicFilter(const std::vector<int>& topics) = 0;
  // Restricts Next() to messages received in [first_ns, last_ns] (all when
  // never called; first_ns > last_ns: none); call before the first Next().
  // Messages outside are not read: a .db3 selects by its timestamp index, an
  // MCAP file skips the chunks outside (mcap::Reader::SetTimeRange).
  virtual Status SetTimeFilter(TimeNs first_ns, TimeNs last_ns) = 0;
  // The next message; false at the end. Errors repeat on later calls.
  virtual StatusOr<bool> Next(RawMessage* out) = 0;
  // One entry per topic (same order as topics()), from a pass that leaves
  // Next() untouched.
  virtual StatusOr<std::vector<RecordingTopicStats>> TopicStats() = 0;
  // All topics together (count, first and last receive time), from the
  // storage's indexes or summary where it has them: no pass over the messages.
  virtual StatusOr<RecordingTopicStats> Span() = 0;
  // Problems that did not stop reading (a cut-short MCAP file).
  virtual std::vector<std::string> warnings() const = 0;
  // The file (or a file of the folder) was cut short: only its complete part
  // is read (an MCAP file without its footer, read by a linear scan).
  virtual bool truncated() const { return false; }
};

}  // namespace rvlio
