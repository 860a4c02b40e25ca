#pragma once
// How `rvlio live` receives and publishes (config section `live`): the queues
// between the network and the estimator, the frames and the topics it
// publishes (docs/live.md). The subscribed topics are lidar.topic and
// imu.topic, as for a recording.
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct LiveOptions {
  std::string odom_frame = "odom";      // world frame of the published poses
  std::string base_frame = "base";      // the IMU frame (child of the odometry and the TF)
  std::string topic_namespace = "/rvlio";  // the published topics: NAMESPACE/odometry, ...
  int scan_queue = 2;          // decoded scans waiting for the estimator, at most
  int imu_queue = 20000;       // IMU samples waiting for the estimator, at most
  double map_period = 2.0;     // s between two publications of the map (0: never)
  double connect_timeout = 5.0;  // s: the ROS 1 master must answer within this
  int ros2_domain_id = -1;     // DDS domain of --ros2 (-1: $ROS_DOMAIN_ID, else 0)
  bool publish_tf = true;      // the TF odom_frame -> base_frame at every pose

  template <class V>
  void Visit(V& v) {
    v.Field("odom_frame", odom_frame, Spec().Help("frame of the published poses (the world frame)"));
    v.Field("base_frame", base_frame,
            Spec().Help("child frame of the published odometry and TF (the IMU frame)"));
    v.Field("topic_namespace", topic_namespace,
            Spec().Help("published topics: NAMESPACE/odometry, odometry_imu, cloud_registered, "
                        "path, map, status (docs/live.md)"));
    v.Field("scan_queue", scan_queue,
            Spec().Range(1, 100).Help("scans waiting for the estimator, at most; when it falls "
                                      "behind the oldest waiting scan is dropped (counted)"));
    v.Field("imu_queue", imu_queue,
            Spec().Range(100, 10000000).Help(
                "IMU samples waiting for the estimator, at most (never dropped while the "
                "estimator keeps up with this many)"));
    v.Field("map_period", map_period,
            Spec().Unit("s").Range(0.0, 3600.0).Help("time between two publications of the map "
                                                     "(0: never)"));
    v.Field("connect_timeout", connect_timeout,
            Spec().Unit("s").Range(0.1, 600.0).Help("--ros1: the master (ROS_MASTER_URI) must "
                                                    "answer within this"));
    v.Field("ros2_domain_id", ros2_domain_id,
            Spec().Range(-1, 232).Help("--ros2: DDS domain id (-1: $ROS_DOMAIN_ID, else 0)"));
    v.Field("publish_tf", publish_tf, Spec().Help("publish the TF odom_frame -> base_frame"));
  }
  Status Validate() {
    if (Status s = ValidateFields(*this, "live"); !s.ok()) return s;
    if (odom_frame.empty() || base_frame.empty() || odom_frame == base_frame)
      return Status::InvalidInput("live.odom_frame and live.base_frame must be two different "
                                  "non-empty names");
    if (topic_namespace.empty() || topic_namespace[0] != '/')
      return Status::InvalidInput("live.topic_namespace must start with '/' (got '" +
                                  topic_namespace + "')");
    return Status::Ok();
  }
};

}  // namespace rvlio
