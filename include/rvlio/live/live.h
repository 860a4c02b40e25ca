#pragma once
// `rvlio live` (target rvlio_live, docs/live.md): the odometry on the robot.
// Subscribes to lidar.topic and imu.topic on a ROS 1 network (roscpp, the
// master of ROS_MASTER_URI) or a ROS 2 one (ROS 2's conventions on Cyclone
// DDS), runs RunRecording's pipeline over them (rvlio/api.h: the same
// estimate as `run` on a recording of the same messages) and publishes, under
// live.topic_namespace: odometry (scan rate), odometry_imu (IMU rate,
// propagated from the latest estimate), cloud_registered, path, map (every
// live.map_period) and status, and the TF live.odom_frame -> live.base_frame.
// When `stop` says so, it writes run's outputs (trajectory.tum, map.pcd,
// scans.csv, summary.json with a "live" section) into out_dir.
#include <cstdint>
#include <functional>
#include <string>

#include "rvlio/api.h"

namespace rvlio {

enum class LiveMiddleware { kRos1, kRos2 };

struct LiveArgs {
  LiveMiddleware middleware = LiveMiddleware::kRos1;
  Configuration options;  // e.g. LoadConfig(files, overrides)
  std::string out_dir;      // as RunArgs::out_dir
  std::string map, initial_pose, initial_pose_tum;  // as RunArgs
  std::string node_name = "rvlio";  // ROS 1 node name (made unique)
  StopFn stop;  // polled (every few ms while waiting): a non-empty string ends the run
  // Called once subscribed and advertising, with where ("ROS 1 master ...").
  std::function<void(const std::string& origin)> on_ready;
  // As RunArgs::progress.
  std::function<void(const RunProgress&)> progress;
};

// What summary.json's "live" section holds (same names).
struct LiveFigures {
  std::string middleware;   // "ros1" or "ros2"
  std::string origin;       // "ROS 1 master http://..." / "ROS 2 on DDS, domain N"
  int64_t lidar_messages = 0, imu_messages = 0;
  int64_t scans_dropped = 0;  // waiting scans dropped: the estimator fell behind
  int64_t imu_dropped = 0;    // past live.imu_queue (estimator stalled)
  int64_t imu_odometry = 0;   // IMU-rate odometry messages published
  double imu_input_hz = 0.0;      // IMU samples received per second (first to last)
  double imu_odometry_hz = 0.0;   // IMU-rate odometry published per second (first to last)
  // From a scan's arrival to the publication of its pose (ms).
  int64_t latency_samples = 0;
  double latency_median_ms = 0.0, latency_p95_ms = 0.0, latency_max_ms = 0.0;
  // Of that, the wait for the IMU sample at or after the scan's end (which
  // the odometry needs before it can estimate the scan): its median; and the
  // time from that sample's arrival to the publication (median, p95).
  double imu_wait_median_ms = 0.0;
  double after_imu_median_ms = 0.0, after_imu_p95_ms = 0.0;
};

struct LiveResult {
  RunResult run;
  LiveFigures figures;
};

// Errors (InvalidInput, one line): the configuration, an unset or silent
// ROS 1 master, no message on a topic within lidar.wait_timeout, a topic of
// the wrong type, the output folder; nothing is written then. A stop before
// the first scan returns run.stopped with no scans.
StatusOr<LiveResult> RunLive(const LiveArgs& args);

}  // namespace rvlio
