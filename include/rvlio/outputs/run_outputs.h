#pragma once
// The files `rvlio run` writes (docs/design.md "The command-line contract"), each atomically.
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/map/map_cloud.h"
#include "rvlio/odometry/deviation.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/outputs/output_stage.h"

namespace rvlio {

// map.pcd stores x y z as float32 while every coordinate is below
// kFloat32MillimetreReach_m (8192 m, math/local_origin.h) in magnitude, else
// as float64 (PCD SIZE 8 TYPE F): a map in a national grid (UTM: eastings of
// 5e5 m, northings of 5e6 m, where a float32 keeps only decimetres) keeps
// its millimetres.
// True when a coordinate of p_world reaches kFloat32MillimetreReach_m.
bool MapNeedsFloat64(const std::vector<Eigen::Vector3d>& p_world);
// The points as map.pcd stores them (rounded to float32 unless
// MapNeedsFloat64): what ReadMapPcd of the written file gives back, without
// the file.
std::vector<Eigen::Vector3d> MapPointsAsStored(std::vector<Eigen::Vector3d> p_world);
// Each coordinate rounded to the nearest float32 (map.pcd's x y z below
// kFloat32MillimetreReach_m).
void RoundToFloat32(std::vector<Eigen::Vector3d>* points);

// Binary PCD (x y z float32, or float64 when MapNeedsFloat64; header made by
// PCL), written atomically: x y z, then the map's attributes (intensity F4,
// time F8 in UNIX seconds, ring U2, scan_index U4: outputs/map_fields.h),
// then the float32 field deviation_m (one per point; NaN allowed) when
// deviation_m is not null: what PCL viewers and CloudCompare show as scalar
// fields (docs/outputs.md "map.pcd"; deviation_m: run --map, docs/survey.md).
Status WriteMapPcd(const std::string& path, const MapCloud& map,
                   const std::vector<double>* deviation_m);
// The same for points without attributes.
Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world);
Status WriteMapPcd(const std::string& path, const std::vector<Eigen::Vector3d>& p_world,
                   const std::vector<double>* deviation_m);
// deviation.csv: one row per chainage bin (odometry/deviation.h).
Status WriteDeviationCsv(const std::string& path, const std::vector<DeviationBin>& bins);
// Reads the points of a map.pcd (any PCD or PLY, point_cloud_file.h: the one
// point-cloud reader; an empty cloud is allowed). InvalidInput naming the
// file for an unreadable, malformed, truncated or non-finite cloud.
StatusOr<std::vector<Eigen::Vector3d>> ReadMapPcd(const std::string& path);
// A map.pcd with its attributes (the fields of outputs/map_fields.h, by
// name; other fields are skipped), read in chunks (PointCloudStream: DATA
// ascii or binary). InvalidInput naming the file for what ReadMapPcd
// refuses, binary_compressed and PLY, a field given twice, a time that is
// not F8, and a ring or scan index that is not a whole number in its range.
struct MapCloudFile {
  MapCloud map;
  bool has_deviation = false;
  std::vector<double> deviation_m;  // one per point with has_deviation
};
StatusOr<MapCloudFile> ReadMapCloud(const std::string& path);

// A stamp in seconds with all nine decimals (the t column of the CSV files).
std::string FormatSeconds(TimeNs t_ns);

// scans.csv: one row per scan, the columns of outputs/scan_columns.h
// (ScanColumnsOf(results)); `rss_mb[i]` is the process's resident memory (MB)
// when scan i was done (nan where rss_mb has no entry).
Status WriteScansCsv(const std::string& path, const std::vector<ScanResult>& results,
                     const std::vector<double>& rss_mb = {});

// A CSV table whose first column is t (scans.csv, localizability.csv): one
// column per header name (NaN where a field is empty or not a number; a
// non-empty `diverged` field counts 1). Header-less or unreadable files are
// InvalidInput naming the file.
struct ScanTable {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  const std::vector<double>* Find(const std::string& name) const;
};
StatusOr<ScanTable> ReadScanTable(const std::string& path);

// The estimated trajectory (IMU in world at each scan end).
Trajectory ToTrajectory(const std::vector<ScanResult>& results);

// trajectory_imu.tum (output.imu_trajectory, docs/outputs.md).
inline constexpr const char* kImuTrajectoryFile = "trajectory_imu.tum";

// trajectory.tum into the stage, and trajectory_imu.tum when imu_trajectory
// is not empty (run, refine, merge). The error is the stage's explanation.
Status WriteTrajectoryOutputs(OutputStage* stage, const Trajectory& trajectory,
                              const Trajectory& imu_trajectory);

// Median, 95th percentile and maximum of the per-scan processing times, ms.
struct TimingStats {
  double median_ms = 0.0, p95_ms = 0.0, max_ms = 0.0, total_ms = 0.0;
};
TimingStats ComputeTimingStats(const std::vector<ScanResult>& results);

}  // namespace rvlio
