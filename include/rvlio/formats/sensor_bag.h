#pragma once
// Recording access for sensor data: ROS1 bags through Debian's rosbag storage
// library, ROS 2 bags (.db3, .mcap, bag folders) through formats/recording.h.
// The estimators never see ROS types: scans and IMU samples come out as the
// library's own types (common/types.h).
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/navsatfix.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

struct OusterMetadata;  // formats/ouster.h

// Counts of what the reader skipped or repaired; reported in summary.json.
struct SensorReaderStats {
  int64_t scans = 0;
  int64_t imu_samples = 0;
  int64_t empty_scans = 0;            // scans with no finite point left (skipped)
  int64_t invalid_points = 0;         // NaN/Inf/zero (no-return) points dropped
  int64_t out_of_range_points = 0;    // outside [lidar.min_range, lidar.max_range], dropped
  int64_t imu_invalid = 0;            // samples with NaN/Inf values (dropped)
  int64_t imu_duplicates = 0;         // samples with the stamp of the previous one (dropped)
  int64_t imu_non_monotonic = 0;      // samples older than the previous one (dropped)
  int64_t imu_gaps = 0;               // gaps longer than imu.max_gap
  int64_t scans_before_first_imu = 0;  // scans delivered before any IMU sample (LiDAR started first)
  double imu_max_gap_s = 0.0;
  // Median span of the point times of the first scans over their median
  // period (-1 until known): about 1 for a sweeping LiDAR.
  double point_time_span_ratio = -1.0;
};

enum class SensorMessage { kImu, kScan, kEnd };

// The messages of a recording received (ROS1 record time, ROS 2 receive /
// MCAP log time) in [first_ns, last_ns], both included; first_ns > last_ns
// selects none. Receive times, not the header stamps the estimators use.
struct ReceiveTimeRange {
  TimeNs first_ns = 0;
  TimeNs last_ns = 0;
};

// Streams IMU samples and decoded scans in bag time order without loading the
// whole bag.
class SensorBagReader {
 public:
  virtual ~SensorBagReader() = default;
  // Fails (InvalidInput) for a missing/unreadable/truncated bag, or a topic
  // that is not there (the message lists the topics that are).
  // With `range`, messages received outside it are neither read nor decoded
  // (ROS1: the bag's index; .db3: an SQL time condition; MCAP: chunks outside
  // are skipped undecompressed; split folders: every file) and count nowhere.
  static StatusOr<std::unique_ptr<SensorBagReader>> Open(
      const std::string& path, const LidarOptions& lidar, const ImuOptions& imu,
      const std::optional<ReceiveTimeRange>& range = std::nullopt);
  // Fills *imu or *scan and says which; kEnd at the end. A scan's points are
  // range-cropped and finite, with absolute per-point times; t_start_ns and
  // t_end_ns are the earliest and latest point times. Messages come in bag
  // record time order; dropped IMU samples and empty scans are skipped (and
  // counted in stats()). A corrupt message or chunk is InvalidInput, and every
  // later call returns the same error.
  virtual StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) = 0;
  virtual const SensorReaderStats& stats() const = 0;
  // "ouster", "velodyne", "hesai" or "livox" (PointCloud2), "livox_custom" (CustomMsg)
  virtual std::string lidar_layout() const = 0;
  // Problems of the recording that did not stop reading (e.g. an MCAP file
  // cut short: its complete part is read); each names the file.
  virtual std::vector<std::string> warnings() const { return {}; }
  // The recording was cut short and only its complete part is read (an MCAP
  // file read by a linear scan); summary.json says "truncated": true.
  virtual bool truncated() const { return false; }
};

// How SensorBagWriter::Create writes.
struct BagWriterOptions {
  // "ros1": a ROS1 .bag (sensor_msgs/PointCloud2, sensor_msgs/Imu);
  // "mcap": a ROS 2 .mcap file; "db3": a ROS 2 sqlite3 .db3 file (both CDR,
  // sensor_msgs/msg/PointCloud2 and sensor_msgs/msg/Imu, ros2msg definitions).
  std::string format = "ros1";
  // MCAP only: chunk compression "zstd", "lz4" or "none", or "unchunked"
  // (messages directly in the data section).
  std::string mcap_compression = "zstd";
};

// Writes sensor data as ROS1 or ROS 2 messages (used by the simulator and
// the tests). Messages are stamped with their receive time: a scan when its
// sweep ends, an IMU sample at its stamp.
class SensorBagWriter {
 public:
  virtual ~SensorBagWriter() = default;
  // Writes to path + ".tmp" and renames on Close(): a failed run leaves no half bag.
  static StatusOr<std::unique_ptr<SensorBagWriter>> Create(const std::string& path,
                                                           const BagWriterOptions& options = {});
  // Ouster driver layout (x y z intensity float32, t uint32 ns from scan start,
  // reflectivity uint16, ring uint16, ambient uint16, range uint32 mm). When
  // scan.points.size() == rows * cols the cloud is organized (rows x cols,
  // row-major by ring, zero points for no-return); otherwise it is 1 x N.
  // The header stamp is scan.t_start_ns.
  virtual Status WriteOusterScan(const std::string& topic, const std::string& frame_id,
                                 const Scan& scan, int rows, int cols) = 0;
  // Livox driver layout (livox_ros_driver/CustomMsg in ROS1,
  // livox_ros_driver2/msg/CustomMsg in ROS 2; formats/livox.h): every point of the
  // scan, timebase and header stamp = scan.t_start_ns.
  virtual Status WriteLivoxScan(const std::string& topic, const std::string& frame_id,
                                const Scan& scan) = 0;
  virtual Status WriteImu(const std::string& topic, const std::string& frame_id,
                          const ImuSample& sample) = 0;
  // sensor_msgs/NavSatFix (ROS1) / sensor_msgs/msg/NavSatFix, received at its
  // header stamp (formats/navsatfix.h).
  virtual Status WriteNavSatFix(const std::string& topic, const NavSatFix& fix) = 0;
  // One Ouster UDP packet as the drivers record it (ouster_ros/PacketMsg in
  // ROS1, ouster_sensor_msgs/msg/PacketMsg in ROS 2: uint8[] buf), received
  // at receive_ns.
  virtual Status WriteOusterPacket(const std::string& topic, TimeNs receive_ns,
                                   const std::vector<uint8_t>& packet) = 0;
  // std_msgs/String (ROS1) / std_msgs/msg/String (the drivers' metadata topic).
  virtual Status WriteString(const std::string& topic, TimeNs receive_ns, const std::string& text) = 0;
  virtual Status Close() = 0;
};

// What `rvlio info` prints.
struct BagTopicInfo {
  std::string topic;
  std::string type;
  int64_t count = 0;
  double rate_hz = 0.0;
  std::string lidar_layout;     // PointCloud2 topics: detected layout
  std::vector<std::string> fields;  // PointCloud2 topics: field names
  double points_per_scan = 0.0;     // PointCloud2 topics: mean points per message
  std::string header_stamp;         // PointCloud2 topics: "start" or "end" (auto-detected)
  std::string decode_error;         // PointCloud2 topics: why the layout is unknown
  int64_t scans_sampled = 0;        // PointCloud2 topics: messages decoded for the figures
};
// An Ouster packet recording (pcap capture or packet bag), from a pass over
// all its packets.
struct OusterRecordingInfo {
  std::string metadata;          // the JSON file or the bag topic it came from
  std::string prod_line, firmware, lidar_mode, lidar_profile;
  std::string imu_profile;       // LEGACY or ACCEL32_GYRO32_NMEA
  bool lidar_decoded = true;     // false: a lidar profile rvlio does not decode
  int beams = 0, columns_per_frame = 0, window_columns = 0;
  std::string lidar_source, imu_source;  // "udp 169.254.10.1 port 7502" or the topic
  int64_t lidar_packets = 0, imu_packets = 0;
  int64_t frames = 0, incomplete_frames = 0, missing_columns = 0;
  int64_t late_packets = 0, crc_errors = 0, imu_crc_errors = 0;
  bool crc = false;              // the packets carry a CRC-64 (checked)
  double imu_rate_hz = 0.0;      // from the IMU packets' own times
  double frame_rate_hz = 0.0;    // from the frames' first column times
};
struct BagInfo {
  std::string path;
  std::string storage;                    // "ros1", "sqlite3" or "mcap"
  // Chunk compressions: MCAP ("zstd", "lz4", "none"), ROS1 ("none", "bz2", "lz4").
  std::vector<std::string> compressions;
  std::vector<std::string> warnings;      // problems that did not stop reading
  double start_s = 0.0, end_s = 0.0;
  TimeNs start_ns = 0, end_ns = 0;  // the same, exact
  int64_t messages = 0;
  std::vector<BagTopicInfo> topics;
  std::optional<OusterRecordingInfo> ouster;  // Ouster packet recordings
};
// Lists every topic of any recording SensorBagReader::Open takes (ROS1 bag,
// .db3, .mcap, ROS 2 bag folder); decodes the first few messages of each
// PointCloud2 topic (only of `lidar_topic` when it is given; it must then be a
// PointCloud2 topic).
// For an Ouster packet recording (a pcap capture: storage "pcap", its UDP
// ports as topics; or a packet bag) also `ouster`, with the metadata
// `ouster_metadata` names ("": found as SensorBagReader::Open finds it).
StatusOr<BagInfo> ReadBagInfo(const std::string& path, const std::string& lidar_topic = "",
                              const std::string& ouster_metadata = "");
// For an Ouster packet recording whose configuration leaves
// extrinsics.imu_T_lidar at its default (identity), sets it from the
// metadata (inverse of imu_to_sensor_transform: rvlio's LiDAR frame is the
// Ouster sensor frame) and appends one line saying so to *notes. Other
// recordings and configured extrinsics are left as they are.
Status ApplyRecordingExtrinsics(const std::string& path, const LidarOptions& lidar,
                                ExtrinsicsSection* extrinsics, std::vector<std::string>* notes);
// The same from metadata at hand (`origin`: where it came from, for the note).
void ApplyOusterExtrinsics(const OusterMetadata& meta, const std::string& origin,
                           ExtrinsicsSection* extrinsics, std::vector<std::string>* notes);

// Only path, storage, messages and the start/end times of ReadBagInfo, from
// the recording's index or summary (no pass over an MCAP file's chunks).
StatusOr<BagInfo> ReadBagSpan(const std::string& path);

}  // namespace rvlio
