#pragma once
// A SensorBagReader over messages that arrive from a network (`rvlio live`,
// docs/live.md "Threads and queues"). A transport (ROS 1, ROS 2 on DDS) hands
// over the serialized bytes of every LiDAR and IMU message as it receives
// them, on its own threads; the estimator's thread reads them with Next() as
// it reads a recording, so `live` runs RunRecording's pipeline unchanged.
// Messages are decoded by the recording readers' decoders (ROS1 wire:
// ros1_messages.h, livox.h; CDR: cdr.h; Ouster packets: the packet
// recordings' decoder and scan assembly, ouster.h) and pass their acceptance
// rules (SensorGate): the same scans and samples as from a recording of them.
//
// Order: IMU samples are delivered as they arrive; a scan is held until an
// IMU sample stamped at or after its end arrived (the odometry waits for that
// sample anyway) and delivered just before it, which is a recording's
// receive-time order (a scan recorded at its end, an IMU sample at its
// stamp), whatever the order in which two network connections deliver them.
// A scan whose covering sample came while it was being decoded is delivered
// at once, after that sample: the odometry estimates it from the same
// samples either way.
//
// Real time: at most live.scan_queue scans wait for the estimator; when one
// more is ready, the oldest waiting scan is dropped (counted). IMU samples
// are not dropped while fewer than live.imu_queue wait.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/live_options.h"
#include "rvlio/formats/ouster.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/imu/options.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

// How a transport serializes messages.
enum class WireEncoding {
  kRos1,  // ROS 1 wire format (as in a .bag)
  kCdr,   // CDR with its encapsulation header (ROS 2)
};

// The message types a live LiDAR topic may carry, by encoding: ROS 1
// ("sensor_msgs/PointCloud2", "livox_ros_driver/CustomMsg",
// "ouster_ros/PacketMsg") or ROS 2 ("sensor_msgs/msg/PointCloud2",
// "livox_ros_driver2/msg/CustomMsg", "ouster_sensor_msgs/msg/PacketMsg",
// "ouster_msgs/msg/PacketMsg").
std::vector<std::string> LiveLidarTypes(WireEncoding encoding);
// An IMU topic: "sensor_msgs/Imu" or "sensor_msgs/msg/Imu", or Ouster IMU
// packets (the packet types above).
std::vector<std::string> LiveImuTypes(WireEncoding encoding);

struct LiveSourceOptions {
  WireEncoding encoding = WireEncoding::kRos1;
  std::string origin;  // where the messages come from, for messages ("ROS 1 master http://...")
  LidarOptions lidar;  // topic, decoding, time_offset, wait_timeout
  ImuOptions imu;
  // The sensor of Ouster packet topics (lidar.ouster_metadata, read by the
  // caller): a packet message without it ends the input with an error.
  std::optional<OusterMetadata> ouster;
  std::string ouster_origin;  // where the metadata came from (its file)
  LiveOptions live;    // scan_queue, imu_queue
  // Polled while Next() waits (every kLivePollMs): true ends the input
  // (Next returns kEnd), e.g. a signal.
  std::function<bool()> stopped;
};
inline constexpr int kLivePollMs = 20;

// What the source dropped or measured (summary.json "live").
struct LiveSourceStats {
  int64_t lidar_messages = 0;
  int64_t imu_messages = 0;
  int64_t scans_dropped = 0;  // waiting scans dropped because the estimator fell behind
  int64_t imu_dropped = 0;    // IMU samples dropped past live.imu_queue (estimator stalled)
};

// A scan handed to the estimator: when its message arrived and its points
// (for the registered cloud), by its end time on the IMU clock.
struct LiveScanArrival {
  TimeNs t_end_ns = 0;
  std::chrono::steady_clock::time_point arrival;
  // When the IMU sample that covers its end arrived (the odometry needs it
  // before it can estimate the scan): arrival or later.
  std::chrono::steady_clock::time_point covered;
  Scan scan;
};

class LiveSensorSource final : public SensorBagReader {
 public:
  explicit LiveSensorSource(LiveSourceOptions options);
  ~LiveSensorSource() override;

  // --- Transport threads (thread-safe) ---
  // An IMU message of type `type`. Returns the samples accepted (for the
  // IMU-rate output): one, or none when dropped; an Ouster IMU packet may
  // hold several. A message of another type, or one that does not decode,
  // ends the input with that error (Fail).
  std::vector<ImuSample> PushImu(const uint8_t* data, size_t size, const std::string& type);
  // A LiDAR message of type `type` received at `arrival`.
  void PushLidar(const uint8_t* data, size_t size, const std::string& type,
                 std::chrono::steady_clock::time_point arrival);
  // Ends the input with an error (the first one is kept): Next returns it.
  void Fail(const Status& status);

  // --- The estimator's thread ---
  // Waits for the next message. InvalidInput naming the topic when its first
  // message does not arrive within lidar.wait_timeout of construction. Once
  // `stopped` says so, the input has ended: the messages received so far are
  // delivered (scans still waiting for the IMU too, and the frame of Ouster
  // packets being assembled, as a recording's last scans are), then kEnd;
  // later messages are ignored.
  StatusOr<SensorMessage> Next(ImuSample* imu, Scan* scan) override;
  const SensorReaderStats& stats() const override;
  std::string lidar_layout() const override;
  // Ouster packets: frames with missing columns, late packets, CRC errors
  // (as a packet recording's reader says them).
  std::vector<std::string> warnings() const override;
  // The scan handed out that ends at t_end_ns (or the latest one before it),
  // with the ones before it forgotten; nothing when none is kept.
  std::optional<LiveScanArrival> TakeArrival(TimeNs t_end_ns);

  LiveSourceStats live_stats() const;
  // The first error of the input (a transport's, a message's), if any.
  Status error() const;

 private:
  struct Item {
    SensorMessage kind = SensorMessage::kImu;
    ImuSample imu;
    Scan scan;
    std::chrono::steady_clock::time_point arrival, covered;
  };
  class Decoder;

  void ReleasePendingScans(TimeNs imu_t_ns);  // mutex_ held
  void QueueImu(const ImuSample& sample);     // mutex_ held
  void FlushAssembly();                       // mutex_ held: the end of the input
  void QueueScan(Item item);                  // mutex_ held
  Status WaitTimeout() const;                 // mutex_ held

  LiveSourceOptions options_;
  std::unique_ptr<Decoder> decoder_;
  const std::chrono::steady_clock::time_point start_;
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::deque<Item> ready_;    // in delivery order
  std::deque<Item> pending_;  // scans waiting for an IMU sample at or after their end
  int ready_scans_ = 0, ready_imu_ = 0;
  bool got_lidar_ = false, got_imu_ = false;
  bool ended_ = false;  // stopped: nothing more is queued
  TimeNs newest_imu_ns_ = std::numeric_limits<TimeNs>::min();  // newest accepted IMU stamp
  Status error_;
  LiveSourceStats live_stats_;
  mutable SensorReaderStats stats_copy_;  // the gate's, read under the mutex
  std::deque<LiveScanArrival> handed_;    // estimator thread only
};

}  // namespace rvlio
