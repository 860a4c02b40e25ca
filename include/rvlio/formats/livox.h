#pragma once
// Livox CustomMsg (livox_ros_driver/CustomMsg in ROS1,
// livox_ros_driver2/msg/CustomMsg in ROS 2: the same fields), free of ROS
// types. The ROS1 reader (formats/sensor_bag_reader) and the CDR decoder (formats/cdr)
// fill this struct; one conversion turns it into a Scan for both.
//
// Per-point time: timebase (ns, absolute) + offset_time (ns, relative).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

struct LivoxCustomPoint {
  uint32_t offset_time = 0;  // ns since timebase
  float x = 0.0f, y = 0.0f, z = 0.0f;
  uint8_t reflectivity = 0;
  uint8_t tag = 0;
  uint8_t line = 0;
};

struct LivoxCustomMsg {
  TimeNs header_stamp_ns = 0;
  std::string frame_id;
  uint64_t timebase = 0;   // ns, time of the first point
  uint32_t point_num = 0;  // as written; the decoder checks it against points.size()
  uint8_t lidar_id = 0;
  std::array<uint8_t, 3> rsvd{};
  std::vector<LivoxCustomPoint> points;
};

// The message definitions, as the drivers declare them (for bag connection
// headers and MCAP schemas).
extern const char kLivoxRos1Type[];     // "livox_ros_driver/CustomMsg"
extern const char kLivoxRos2Type[];     // "livox_ros_driver2/msg/CustomMsg"
extern const char kLivoxRos1Md5[];      // ROS1 md5sum of livox_ros_driver/CustomMsg
extern const char kLivoxRos1Definition[];  // its full ROS1 definition (with Header, CustomPoint)

// ROS1 wire format of livox_ros_driver/CustomMsg (little endian, packed):
// Header{seq u32, stamp sec u32 nsec u32, frame_id u32 length + bytes},
// timebase u64, point_num u32, lidar_id u8, rsvd u8[3], points as u32 count +
// 19-byte CustomPoint{offset_time u32, x y z float32, reflectivity tag line u8}.
// Parse: InvalidInput (naming `what`) for a short, over-long or trailing-byte
// payload; point_num is not checked here (DecodeLivoxCustomMsg does).
StatusOr<LivoxCustomMsg> ParseLivoxRos1(const uint8_t* data, size_t size,
                                        const std::string& what = "CustomMsg");
std::vector<uint8_t> SerializeLivoxRos1(const LivoxCustomMsg& msg);

// A CustomMsg -> Scan with absolute per-point times, dropping invalid and
// out-of-range points exactly as DecodePointCloud2 does (stats->layout is
// "livox_custom"). InvalidInput when point_num disagrees with the points.
StatusOr<Scan> DecodeLivoxCustomMsg(const LivoxCustomMsg& msg, const LidarOptions& lidar,
                                    DecodeStats* stats = nullptr);

// A Scan -> CustomMsg (timebase = scan.t_start_ns), for the simulator.
LivoxCustomMsg ScanToLivoxCustomMsg(const Scan& scan, const std::string& frame_id);

}  // namespace rvlio
