#pragma once
// A ROS-free decoder of sensor_msgs/PointCloud2 payloads into Scans with
// absolute per-point times. The bag reader hands it a view of the message;
// tests and fuzzers hand it arbitrary bytes: every offset, stride and size is
// validated before a byte is read.
//
// Supported per-point time layouts (lidar.type):
//   ouster    `t`            uint32, ns relative to the header stamp (scan start)
//   velodyne  `time`         float32, s relative to the header stamp (negative
//                            when the stamp marks the scan end)
//   hesai     `timestamp`    float64, absolute s
//   livox     `timestamp`    float64, absolute ns or s (detected), or
//             `offset_time`  uint32, ns relative to the header stamp
// `auto` detects the layout from the field names.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

// sensor_msgs/PointField datatype codes.
enum PointFieldType : uint8_t {
  kPointInt8 = 1,
  kPointUint8 = 2,
  kPointInt16 = 3,
  kPointUint16 = 4,
  kPointInt32 = 5,
  kPointUint32 = 6,
  kPointFloat32 = 7,
  kPointFloat64 = 8,
};
// Size in bytes of one element of a datatype; 0 for an unknown code.
size_t PointFieldSize(uint8_t datatype);

struct PointField {
  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;
  uint32_t count = 1;
};

// Non-owning view of one PointCloud2 message.
struct PointCloud2View {
  TimeNs header_stamp_ns = 0;
  uint32_t height = 0, width = 0, point_step = 0, row_step = 0;
  bool is_bigendian = false;
  std::vector<PointField> fields;
  const uint8_t* data = nullptr;
  size_t data_size = 0;
  std::string topic;  // only for error messages; may be empty
};

// What the decoder found and dropped in one message.
struct DecodeStats {
  std::string layout;          // "ouster", "velodyne", "hesai" or "livox"
  bool stamp_is_end = false;   // the header stamp marks the scan end
  int64_t raw_points = 0;      // height * width
  int64_t invalid_points = 0;  // NaN/Inf coordinates or time, all-zero (no-return)
  int64_t out_of_range_points = 0;  // outside [lidar.min_range, lidar.max_range]
  bool fast_path = false;  // decoded by the typed loop of the common layouts (below)
};

// Returns the layout lidar.type selects for these fields ("auto" detects it),
// or InvalidInput naming the fields when there is no usable time field.
StatusOr<std::string> DetectPointCloud2Layout(const PointCloud2View& cloud,
                                              const std::string& type);

// Decodes a cloud: finite, non-zero, range-cropped points with absolute times
// (the header stamp plus the relative time, or the absolute time field).
// Scan.t_start_ns / t_end_ns are the earliest / latest kept point times (the
// header stamp when no point is left). `stats` may be null.
//
// lidar.header_stamp, relative layouts only (absolute layouts carry their own
// times and only report what the stamp matches):
//   auto   t = stamp + rel; the stamp is the end when most rel are negative
//   start  the stamp is the scan start: shifted so the earliest rel is 0 when
//          the rel are mostly negative, else t = stamp + rel
//   end    the stamp is the scan end: shifted so the latest rel is 0 when the
//          rel are mostly non-negative, else t = stamp + rel
//
// The common layouts take a fast path with the same result: host byte order,
// x, y, z float32, a relative time field in uint32 ns (Ouster `t`, Livox
// `offset_time`) or float32 s (Velodyne `time`), intensity float32 or absent,
// ring (or Livox line) uint8, uint16 or absent. The
// layout is checked once per message (a few field-name compares); the points
// are then read at fixed offsets with fixed types. Any other layout (another
// byte order or datatype, absolute times) goes through the generic reader.
StatusOr<Scan> DecodePointCloud2(const PointCloud2View& cloud, const LidarOptions& lidar,
                                 DecodeStats* stats = nullptr);
// DecodePointCloud2 with the fast path off: every layout through the generic
// reader (the reference the fast path is tested and benchmarked against).
StatusOr<Scan> DecodePointCloud2Generic(const PointCloud2View& cloud, const LidarOptions& lidar,
                                        DecodeStats* stats = nullptr);

// The point filter of DecodePointCloud2, shared with the other decoders
// (formats/livox): false, counted in stats->invalid_points, for a non-finite, huge
// (>= 1e9 m) or all-zero (no-return) point or one without a usable time
// (time_ok false); false, counted in stats->out_of_range_points, outside
// [lidar.min_range, lidar.max_range]. *p_lidar receives the float point.
bool FilterPoint(double x, double y, double z, bool time_ok, const LidarOptions& lidar,
                 DecodeStats* stats, Eigen::Vector3f* p_lidar);

// t_start_ns / t_end_ns = the earliest / latest point time, or fallback_ns
// for a scan without points.
void SetScanTimeBounds(TimeNs fallback_ns, Scan* scan);

// "x,y,z,intensity" for messages.
std::string PointFieldNames(const std::vector<PointField>& fields);

}  // namespace rvlio
