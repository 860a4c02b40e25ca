#pragma once
// LiDAR input and preprocessing options.
#include <cmath>
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct LidarOptions {
  std::string topic = "/os_cloud_node/points";
  std::string type = "auto";          // auto | ouster | velodyne | hesai | livox
  std::string header_stamp = "auto";  // auto | start | end: what the header stamp marks
  double min_range = 0.5;             // m, points closer are dropped (sensor body)
  double max_range = 100.0;           // m
  double voxel_size = 0.5;            // m, scan downsampling before association
  int point_stride = 1;               // keep every n-th raw point before the voxel filter
  double time_offset = 0.0;           // s, t_imu_clock = t_lidar_stamp + time_offset
  // Point-time sanity check (formats/sensor_bag.h): the span of the point times of
  // a scan against the scan period, median over the first scans.
  double point_time_span_stop = 0.01;  // below this fraction reading stops (0: never)
  double point_time_span_warn = 0.5;   // below this fraction a warning
  double wait_timeout = 10.0;         // s: rvlio live waits this long for the first message of each topic
  std::string ouster_metadata;        // Ouster metadata JSON of a packet recording ("" = find it)
  // Online estimation of time_offset (docs/time_offset.md): an augmented state
  // of the IESKF, one parameter of the smoother's window.
  bool estimate_time_offset = false;
  double time_offset_max = 0.2;            // s, |estimate| bound (reported when reached)
  double time_offset_init_std = 0.05;      // s, prior std around time_offset
  double time_offset_random_walk = 1e-4;   // s/sqrt(s), process noise of the estimate
  double time_offset_excited_std = 0.002;  // s, 1-sigma under which an excited estimate is trusted
  // IESKF map hold (docs/time_offset.md "Map hold"): the first moving scans
  // are provisional in the working map until the estimate's 1-sigma falls
  // below time_offset_map_std (then the map returns to its state before the
  // motion), for at most time_offset_map_hold seconds of motion (0: off).
  double time_offset_map_hold = 0.0;    // s (0: off)
  double time_offset_map_std = 0.001;   // s
  // IESKF replay (docs/time_offset.md "Replay"): the input from the start of
  // the motion is kept with a snapshot of the filter; once the estimate's
  // 1-sigma falls below time_offset_replay_std, the filter returns to the
  // snapshot with the converged offset and re-processes it. Given up after
  // time_offset_replay seconds of motion without convergence (0: off). The
  // early 1-sigma is optimistic (hall, +100 ms: 0.75 ms while the estimate is
  // still 30 ms off), hence a threshold well below time_offset_map_std.
  double time_offset_replay = 2.0;        // s (0: off)
  double time_offset_replay_std = 1e-4;   // s

  template <class V>
  void Visit(V& v) {
    v.Field("topic", topic, Spec().Help("PointCloud2 or Livox CustomMsg topic in the bag"));
    v.Field("type", type, Spec().Choices({"auto", "ouster", "velodyne", "hesai", "livox"})
                              .Help("per-point time layout; auto detects it from the field names"));
    v.Field("header_stamp", header_stamp, Spec().Choices({"auto", "start", "end"})
                              .Help("whether the header stamp marks scan start or end; auto detects it from the time field"));
    v.Field("min_range", min_range, Spec().Unit("m").Range(0.0, 1000.0).Help("minimum point range"));
    v.Field("max_range", max_range, Spec().Unit("m").Positive().Help("maximum point range"));
    v.Field("voxel_size", voxel_size, Spec().Unit("m").Range(0.0, 10.0).Help("scan voxel downsampling (0: off)"));
    v.Field("point_stride", point_stride, Spec().Range(1, 1000).Help("keep every n-th raw point"));
    v.Field("time_offset", time_offset,
            Spec().Unit("s").Range(-10.0, 10.0).Help(
                "added to every LiDAR time to put it on the IMU clock: t_imu = t_lidar_stamp + "
                "time_offset (LiDAR stamps 30 ms behind the IMU clock: 0.03)"));
    v.Field("point_time_span_stop", point_time_span_stop,
            Spec().Range(0.0, 1.0).Help(
                "reading stops when the point times of a scan span less than this fraction of "
                "the scan period (median of the first scans: times all zero, or not in "
                "nanoseconds); 0: never"));
    v.Field("point_time_span_warn", point_time_span_warn,
            Spec().Range(0.0, 1.0).Help(
                "a warning when the point times of a scan span less than this fraction of the "
                "scan period (median of the first scans)"));
    v.Field("wait_timeout", wait_timeout,
            Spec().Unit("s").Range(0.1, 3600.0).Help(
                "rvlio live: the first message on lidar.topic and on imu.topic must arrive "
                "within this (else exit 2 naming the topic)"));
    v.Field("ouster_metadata", ouster_metadata,
            Spec().Help("Ouster sensor metadata JSON for a packet recording (pcap capture or "
                        "packet bag); empty: NAME.json / NAME_0.json next to a capture, the "
                        "bag's metadata topic (CLI: --ouster-metadata)"));
    v.Field("estimate_time_offset", estimate_time_offset,
            Spec().Help("estimate the LiDAR-IMU time offset online, starting from time_offset "
                        "(scans.csv time_offset_s, summary.json time_offset)"));
    v.Field("time_offset_max", time_offset_max,
            Spec().Unit("s").Range(0.001, 10.0).Help(
                "bound of the estimated time offset; an estimate reaching it is held there and "
                "reported (warning, summary.json time_offset.at_bound)"));
    v.Field("time_offset_init_std", time_offset_init_std,
            Spec().Unit("s").Range(1e-6, 10.0).Help("prior std of the estimated time offset"));
    v.Field("time_offset_random_walk", time_offset_random_walk,
            Spec().Unit("s/sqrt(s)").Range(0.0, 1.0).Help(
                "process noise of the estimated time offset (clock drift)"));
    v.Field("time_offset_excited_std", time_offset_excited_std,
            Spec().Unit("s").Range(1e-6, 1.0).Help(
                "the estimate counts as trustworthy once excited and its 1-sigma is below this"));
    v.Field("time_offset_map_hold", time_offset_map_hold,
            Spec().Unit("s").Range(0.0, 60.0).Help(
                "IESKF with estimate_time_offset: the first moving scans are provisional in the "
                "map, which returns to its state before the motion once the estimate converges "
                "(time_offset_map_std), for at most this long; 0: off"));
    v.Field("time_offset_map_std", time_offset_map_std,
            Spec().Unit("s").Range(1e-6, 1.0).Help(
                "IESKF map hold: the estimate counts as converged once its 1-sigma is below this"));
    v.Field("time_offset_replay", time_offset_replay,
            Spec().Unit("s").Range(0.0, 60.0).Help(
                "IESKF with estimate_time_offset: once the estimate converges "
                "(time_offset_replay_std), the scans since the motion started are processed again "
                "with it; given up after this long without convergence; 0: off"));
    v.Field("time_offset_replay_std", time_offset_replay_std,
            Spec().Unit("s").Range(1e-7, 1.0).Help(
                "IESKF replay: the estimate counts as converged once its 1-sigma is below this"));
  }
  Status Validate() {
    Status s = ValidateFields(*this, "lidar");
    if (s.ok() && !(max_range > min_range))
      return Status::InvalidInput("lidar.max_range must be greater than lidar.min_range");
    if (s.ok() && estimate_time_offset && std::abs(time_offset) > time_offset_max)
      return Status::InvalidInput("lidar.time_offset (" + std::to_string(time_offset) +
                                  " s) is outside lidar.time_offset_max (" +
                                  std::to_string(time_offset_max) + " s)");
    return s;
  }
};

}  // namespace rvlio
