// Livox CustomMsg: the ROS1 wire format (written from the ROS1 serialization
// rules and the driver's .msg files) and the conversion to and from Scans.
#include "rvlio/formats/livox.h"

#include "ros1_wire.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace rvlio {

const char kLivoxRos1Type[] = "livox_ros_driver/CustomMsg";
const char kLivoxRos2Type[] = "livox_ros_driver2/msg/CustomMsg";

// ROS1 md5: over the comment-free definition with the nested types replaced
// by their md5s: "2176decaecbce78abc3b96ef049fabed header\nuint64 timebase\n
// uint32 point_num\nuint8 lidar_id\nuint8[3] rsvd\n<CustomPoint md5> points",
// where CustomPoint's md5 (109a3cc548bb1f96626be89a5008bd6d) is over
// "uint32 offset_time\nfloat32 x\nfloat32 y\nfloat32 z\nuint8 reflectivity\n
// uint8 tag\nuint8 line". The value is the one the driver's bags carry.
const char kLivoxRos1Md5[] = "e4d6829bdfe657cb6c21a746c86b21a6";

// The driver's CustomMsg.msg followed by its dependencies, as ROS1 tools
// write message definitions into bag connection headers.
const char kLivoxRos1Definition[] =
    "# Livox publish pointcloud msg format.\n"
    "\n"
    "Header header             # ROS standard message header\n"
    "uint64 timebase           # The time of first point\n"
    "uint32 point_num          # Total number of pointclouds\n"
    "uint8  lidar_id           # Lidar device id number\n"
    "uint8[3]  rsvd            # Reserved use\n"
    "CustomPoint[] points      # Pointcloud data\n"
    "\n"
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "# Standard metadata for higher-level stamped data types.\n"
    "# This is generally used to communicate timestamped data \n"
    "# in a particular coordinate frame.\n"
    "# \n"
    "# sequence ID: consecutively increasing ID \n"
    "uint32 seq\n"
    "#Two-integer timestamp that is expressed as:\n"
    "# * stamp.sec: seconds (stamp_secs) since epoch (in Python the variable is called 'secs')\n"
    "# * stamp.nsec: nanoseconds since stamp_secs (in Python the variable is called 'nsecs')\n"
    "# time-handling sugar is provided by the client library\n"
    "time stamp\n"
    "#Frame this data is associated with\n"
    "string frame_id\n"
    "\n"
    "================================================================================\n"
    "MSG: livox_ros_driver/CustomPoint\n"
    "# Livox costom pointcloud format.\n"
    "\n"
    "uint32 offset_time      # offset time relative to the base time\n"
    "float32 x               # X axis, unit:m\n"
    "float32 y               # Y axis, unit:m\n"
    "float32 z               # Z axis, unit:m\n"
    "uint8 reflectivity      # reflectivity, 0~255\n"
    "uint8 tag               # livox tag\n"
    "uint8 line              # laser number in lidar\n";

namespace {

constexpr size_t kPointBytes = 19;
// Absolute times must fit int64 nanoseconds with room for arithmetic (as in
// the PointCloud2 decoder).
constexpr uint64_t kMaxAbsoluteNs = 2000000000000000000ull;

using bag_detail::Ros1WireReader;
using bag_detail::Ros1WireWriter;

bool ReadPoint(Ros1WireReader& r, LivoxCustomPoint* p) {
  return r.Read(&p->offset_time) && r.Read(&p->x) && r.Read(&p->y) && r.Read(&p->z) &&
         r.Read(&p->reflectivity) && r.Read(&p->tag) && r.Read(&p->line);
}

}  // namespace

StatusOr<LivoxCustomMsg> ParseLivoxRos1(const uint8_t* data, size_t size,
                                        const std::string& what) {
  Ros1WireReader r(data, size);
  LivoxCustomMsg msg;
  uint32_t count = 0;
  if (!r.ReadHeader(&msg.header_stamp_ns, &msg.frame_id) || !r.Read(&msg.timebase) ||
      !r.Read(&msg.point_num) || !r.Read(&msg.lidar_id) || !r.Read(&msg.rsvd[0]) || !r.Read(&msg.rsvd[1]) || !r.Read(&msg.rsvd[2]) || !r.Read(&count))
    return Status::InvalidInput(what + ": message of " + std::to_string(size) +
                                " bytes is too short for a livox_ros_driver/CustomMsg header");
  if (r.remaining() / kPointBytes < count)
    return Status::InvalidInput(what + ": " + std::to_string(count) + " points need " +
                                std::to_string(uint64_t{count} * kPointBytes) + " bytes, " +
                                std::to_string(r.remaining()) + " left");
  msg.points.resize(count);
  for (LivoxCustomPoint& p : msg.points) ReadPoint(r, &p);
  if (r.remaining() != 0)
    return Status::InvalidInput(what + ": " + std::to_string(r.remaining()) +
                                " bytes after the last point");
  return msg;
}

std::vector<uint8_t> SerializeLivoxRos1(const LivoxCustomMsg& msg) {
  Ros1WireWriter w;
  w.Reserve(40 + msg.frame_id.size() + msg.points.size() * kPointBytes);
  const TimeNs stamp = std::max<TimeNs>(msg.header_stamp_ns, 0);
  w.Write(uint32_t{0});  // seq
  w.Write(static_cast<uint32_t>(stamp / kNsPerSecond));
  w.Write(static_cast<uint32_t>(stamp % kNsPerSecond));
  w.WriteString(msg.frame_id);
  w.Write(msg.timebase);
  w.Write(msg.point_num);
  w.Write(msg.lidar_id);
  for (uint8_t b : msg.rsvd) w.Write(b);
  w.Write(static_cast<uint32_t>(msg.points.size()));
  for (const LivoxCustomPoint& p : msg.points) {
    w.Write(p.offset_time);
    w.Write(p.x);
    w.Write(p.y);
    w.Write(p.z);
    w.Write(p.reflectivity);
    w.Write(p.tag);
    w.Write(p.line);
  }
  return w.Take();
}

StatusOr<Scan> DecodeLivoxCustomMsg(const LivoxCustomMsg& msg, const LidarOptions& lidar,
                                    DecodeStats* stats_out) {
  DecodeStats local;
  DecodeStats* stats = stats_out ? stats_out : &local;
  *stats = DecodeStats();
  if (lidar.type != "auto" && lidar.type != "livox")
    return Status::InvalidInput("lidar.type=" + lidar.type + " does not apply to a Livox " +
                                "CustomMsg (use auto or livox)");
  if (msg.point_num != msg.points.size())
    return Status::InvalidInput("Livox CustomMsg: point_num " + std::to_string(msg.point_num) +
                                " disagrees with the " + std::to_string(msg.points.size()) +
                                " points it holds");
  if (msg.timebase > kMaxAbsoluteNs ||
      static_cast<uint64_t>(std::abs(msg.header_stamp_ns)) > kMaxAbsoluteNs)
    return Status::InvalidInput("Livox CustomMsg: timebase or header stamp out of range");
  stats->layout = "livox_custom";
  stats->raw_points = static_cast<int64_t>(msg.points.size());
  const TimeNs timebase_ns = static_cast<TimeNs>(msg.timebase);
  Scan scan;
  scan.points.reserve(msg.points.size());
  for (const LivoxCustomPoint& in : msg.points) {
    LidarPoint p;
    if (!FilterPoint(in.x, in.y, in.z, true, lidar, stats, &p.p_lidar)) continue;
    p.t_ns = timebase_ns + static_cast<TimeNs>(in.offset_time);
    p.intensity = in.reflectivity;
    p.ring = in.line;
    scan.points.push_back(p);
  }
  SetScanTimeBounds(msg.header_stamp_ns, &scan);
  scan.has_intensity = true;  // reflectivity
  scan.has_ring = true;       // line
  return scan;
}

LivoxCustomMsg ScanToLivoxCustomMsg(const Scan& scan, const std::string& frame_id) {
  LivoxCustomMsg msg;
  msg.header_stamp_ns = scan.t_start_ns;
  msg.frame_id = frame_id;
  msg.timebase = static_cast<uint64_t>(std::max<TimeNs>(scan.t_start_ns, 0));
  msg.points.reserve(scan.points.size());
  constexpr TimeNs kMaxOffset = std::numeric_limits<uint32_t>::max();
  for (const LidarPoint& in : scan.points) {
    LivoxCustomPoint p;
    const TimeNs dt = in.t_ns - scan.t_start_ns;
    p.offset_time = static_cast<uint32_t>(std::clamp<TimeNs>(dt, 0, kMaxOffset));
    p.x = in.p_lidar.x();
    p.y = in.p_lidar.y();
    p.z = in.p_lidar.z();
    p.reflectivity = std::isfinite(in.intensity)
                         ? static_cast<uint8_t>(std::clamp(std::lround(in.intensity), 0l, 255l))
                         : uint8_t{0};
    p.line = static_cast<uint8_t>(std::min<int>(in.ring, 255));
    msg.points.push_back(p);
  }
  msg.point_num = static_cast<uint32_t>(msg.points.size());
  return msg;
}

}  // namespace rvlio
