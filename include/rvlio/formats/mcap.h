#pragma once
// MCAP container (https://mcap.dev/spec, format version 0), written from the
// public specification: no Debian package exists. Reader and writer of the
// records rvlio needs: Header/Footer/magic, Schema, Channel, Message, Chunk
// (compression "", "zstd", "lz4" = LZ4 frame format), MessageIndex,
// ChunkIndex, Statistics, SummaryOffset, DataEnd; other records are skipped by
// their length as the specification requires.
//
// The reader uses the summary section (chunk indexes, statistics) when the
// file has one and falls back to a linear scan of the data section when it
// does not (a recording cut short). Every CRC that is present (non-zero) is
// checked. Errors are Status::InvalidInput naming the file and the byte
// offset of the record at fault. No ROS types here: message payloads are
// opaque bytes (CDR for ROS 2, decoded in formats/cdr).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "rvlio/common/status.h"

namespace rvlio::mcap {

struct Schema {
  uint16_t id = 0;
  std::string name;      // e.g. "sensor_msgs/msg/PointCloud2"
  std::string encoding;  // e.g. "ros2msg"
  std::string data;      // the message definition text (may be empty)
};

struct Channel {
  uint16_t id = 0;
  uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // e.g. "cdr"
  std::map<std::string, std::string> metadata;
};

struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time_ns = 0;
  uint64_t publish_time_ns = 0;
  std::vector<uint8_t> data;
};

// What the file says of itself, for `rvlio info` and the tests.
struct FileSummary {
  std::string profile;             // Header.profile, "ros2" for rosbag2
  std::string library;             // Header.library
  bool has_summary = false;        // false: the data section was scanned linearly
  bool truncated = false;          // the file ends before its Footer / mid-record
  uint64_t message_count = 0;      // Statistics, or counted by the linear scan
  uint64_t message_start_time_ns = 0;
  uint64_t message_end_time_ns = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
  uint64_t chunk_count = 0;
  std::vector<std::string> compressions;  // distinct chunk compressions ("" = none)
};

class Reader {
 public:
  virtual ~Reader() = default;
  // Fails for a missing file, bad magic, or a corrupt summary. A file without
  // a summary (cut short) opens; summary().truncated tells.
  static StatusOr<std::unique_ptr<Reader>> Open(const std::string& path);
  // The same on bytes in memory (`name` stands for the path in messages):
  // one code path for files, tests and the fuzzer.
  static StatusOr<std::unique_ptr<Reader>> OpenBuffer(std::string bytes, const std::string& name);

  virtual const FileSummary& summary() const = 0;
  virtual const std::map<uint16_t, Schema>& schemas() const = 0;
  virtual const std::map<uint16_t, Channel>& channels() const = 0;

  // Restricts Next() to these channels (all when never called). Chunks with
  // none of them are not decompressed when the summary's indexes tell so.
  virtual void SetChannelFilter(const std::vector<uint16_t>& channel_ids) = 0;
  // Restricts Next() to messages with first_ns <= log time <= last_ns (all
  // when never called; first_ns > last_ns: none). Chunks and runs of loose
  // messages whose time span (chunk index or chunk header) lies outside are
  // neither read nor decompressed.
  virtual void SetTimeRange(uint64_t first_ns, uint64_t last_ns) = 0;
  // The next message in log-time order (ties: file order); false at the end.
  // Messages of a truncated tail record are not returned; a CRC mismatch or a
  // malformed record is an error, and later calls return it again.
  virtual StatusOr<bool> Next(Message* out) = 0;
  // Problems that did not stop reading (e.g. "no summary section: read by a
  // linear scan; the file may have been cut short").
  virtual std::vector<std::string> warnings() const = 0;
  // Chunks Next() has decompressed so far (chunks the channel filter rules
  // out by the summary's message indexes are not).
  virtual uint64_t chunks_loaded() const = 0;
};

struct WriterOptions {
  std::string compression = "zstd";  // "", "zstd" or "lz4"
  bool chunked = true;               // false: messages directly in the data section
  uint64_t chunk_size = 4 << 20;     // bytes of uncompressed records per chunk
  std::string profile = "ros2";
  std::string library = "rvlio";
};

class Writer {
 public:
  virtual ~Writer() = default;
  // Writes to a temporary file next to `path` (AtomicFileWriter) and renames
  // it on Close(): a failed write (a full disk) returns its Status and leaves
  // no half file behind.
  static StatusOr<std::unique_ptr<Writer>> Create(const std::string& path,
                                                  const WriterOptions& options);
  virtual StatusOr<uint16_t> AddSchema(const std::string& name, const std::string& encoding,
                                       const std::string& data) = 0;
  virtual StatusOr<uint16_t> AddChannel(uint16_t schema_id, const std::string& topic,
                                        const std::string& message_encoding) = 0;
  virtual Status Write(const Message& message) = 0;
  // Flushes the last chunk, writes message indexes, the summary section
  // (schemas, channels, statistics, chunk indexes, summary offsets) and the
  // footer with CRCs, then renames into place.
  virtual Status Close() = 0;
};

}  // namespace rvlio::mcap
