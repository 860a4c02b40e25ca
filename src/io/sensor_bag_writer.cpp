// SensorBagWriter: ROS1 messages through rosbag::Bag, written to path + ".tmp"
// and renamed into place on Close().
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>

#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include "livox_ros1.h"
#include "rosbag_common.h"
#include "rvlio/io/sensor_bag.h"

namespace rvlio {
namespace {

// Largest time a ROS1 stamp (uint32 seconds) can hold.
constexpr TimeNs kMaxRosNs = static_cast<TimeNs>(std::numeric_limits<uint32_t>::max()) * kNsPerSecond;

// The Ouster driver's point (ouster_ros): x y z at 0/4/8, padding, intensity
// at 16, t at 20, reflectivity 24, ring 26, ambient 28, range 32; 48 bytes.
struct OusterField {
  const char* name;
  uint32_t offset;
  uint8_t datatype;
};
constexpr OusterField kOusterFields[] = {
    {"x", 0, sensor_msgs::PointField::FLOAT32},
    {"y", 4, sensor_msgs::PointField::FLOAT32},
    {"z", 8, sensor_msgs::PointField::FLOAT32},
    {"intensity", 16, sensor_msgs::PointField::FLOAT32},
    {"t", 20, sensor_msgs::PointField::UINT32},
    {"reflectivity", 24, sensor_msgs::PointField::UINT16},
    {"ring", 26, sensor_msgs::PointField::UINT16},
    {"ambient", 28, sensor_msgs::PointField::UINT16},
    {"range", 32, sensor_msgs::PointField::UINT32},
};
constexpr uint32_t kOusterPointStep = 48;

template <typename T>
void Put(uint8_t* dst, uint32_t offset, T value) {
  std::memcpy(dst + offset, &value, sizeof(T));
}

bool IsNoReturn(const LidarPoint& p) { return p.p_lidar.isZero(0.0f); }

uint16_t ClampU16(double v) {
  if (!(v > 0.0)) return 0;
  return v >= 65535.0 ? uint16_t{65535} : static_cast<uint16_t>(std::lround(v));
}

Status CheckStamp(TimeNs t_ns, const std::string& what) {
  if (t_ns < 0 || t_ns > kMaxRosNs) {
    return Status::InvalidInput(what + " " + std::to_string(t_ns) +
                                " ns is outside the ROS1 time range [0, 2^32 s)");
  }
  return Status::Ok();
}

// Relative time field `t` of one point (ns from the scan start). A no-return
// point keeps whatever time it has when it fits, else 0.
Status RelativeTime(const Scan& scan, const LidarPoint& p, size_t index, uint32_t* t) {
  const TimeNs dt = p.t_ns - scan.t_start_ns;
  if (dt >= 0 && dt <= static_cast<TimeNs>(std::numeric_limits<uint32_t>::max())) {
    *t = static_cast<uint32_t>(dt);
    return Status::Ok();
  }
  if (IsNoReturn(p)) {
    *t = 0;
    return Status::Ok();
  }
  return Status::InvalidInput("point " + std::to_string(index) + " time " +
                              std::to_string(p.t_ns) + " ns is not within 4.29 s after the scan "
                              "start " + std::to_string(scan.t_start_ns) + " ns");
}

Status FillOusterCloud(const Scan& scan, int rows, int cols, sensor_msgs::PointCloud2* msg) {
  const size_t n = scan.points.size();
  const bool organized = rows > 0 && cols > 0 && static_cast<size_t>(rows) * cols == n;
  msg->height = organized ? rows : 1;
  msg->width = organized ? cols : static_cast<uint32_t>(n);
  msg->is_bigendian = false;
  msg->is_dense = !organized;
  msg->point_step = kOusterPointStep;
  msg->row_step = kOusterPointStep * msg->width;
  for (const auto& f : kOusterFields) {
    sensor_msgs::PointField field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = 1;
    msg->fields.push_back(field);
  }
  msg->data.assign(n * kOusterPointStep, 0);
  for (size_t i = 0; i < n; ++i) {
    const LidarPoint& p = scan.points[i];
    uint32_t t = 0;
    if (Status s = RelativeTime(scan, p, i, &t); !s.ok()) return s;
    uint8_t* dst = msg->data.data() + i * kOusterPointStep;
    Put<float>(dst, 0, p.p_lidar.x());
    Put<float>(dst, 4, p.p_lidar.y());
    Put<float>(dst, 8, p.p_lidar.z());
    Put<float>(dst, 16, p.intensity);
    Put<uint32_t>(dst, 20, t);
    Put<uint16_t>(dst, 24, ClampU16(p.intensity));
    Put<uint16_t>(dst, 26, p.ring);
    Put<uint16_t>(dst, 28, 0);
    const double range_mm = 1000.0 * p.p_lidar.cast<double>().norm();
    Put<uint32_t>(dst, 32, std::isfinite(range_mm) && range_mm < 4.0e9
                               ? static_cast<uint32_t>(std::lround(range_mm)) : 0u);
  }
  return Status::Ok();
}

class RosbagSensorWriter final : public SensorBagWriter {
 public:
  explicit RosbagSensorWriter(std::string path) : path_(std::move(path)), tmp_(path_ + ".tmp") {}
  ~RosbagSensorWriter() override {
    if (!open_) return;
    std::string why;
    (void)CloseBag(&why);
    std::remove(tmp_.c_str());
  }

  Status Init() {
    bag_ = std::make_unique<rosbag::Bag>();
    try {
      bag_->open(tmp_, rosbag::bagmode::Write);
    } catch (const std::exception& e) {
      std::string ignored;
      (void)CloseBag(&ignored);  // a half-opened Bag may still hold the file
      std::remove(tmp_.c_str());
      return Status::InvalidInput("cannot write bag '" + tmp_ + "' (" + e.what() + ")");
    }
    open_ = true;
    return Status::Ok();
  }

  Status WriteOusterScan(const std::string& topic, const std::string& frame_id, const Scan& scan,
                         int rows, int cols) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckStamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckStamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    sensor_msgs::PointCloud2 msg;
    msg.header.stamp.fromNSec(static_cast<uint64_t>(scan.t_start_ns));
    msg.header.frame_id = frame_id;
    if (Status s = FillOusterCloud(scan, rows, cols, &msg); !s.ok()) return s;
    // Recorded when the driver publishes it: at the end of the sweep.
    return Write(topic, bag_detail::RecordTime(scan.t_end_ns), msg);
  }

  Status WriteLivoxScan(const std::string& topic, const std::string& frame_id,
                        const Scan& scan) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckStamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckStamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    for (size_t i = 0; i < scan.points.size(); ++i) {
      uint32_t t = 0;  // offset_time must fit uint32 ns after the timebase
      if (Status s = RelativeTime(scan, scan.points[i], i, &t); !s.ok()) return s;
    }
    bag_detail::LivoxRos1Bytes msg{SerializeLivoxRos1(ScanToLivoxCustomMsg(scan, frame_id))};
    // Recorded when the driver publishes it: at the end of the sweep.
    return Write(topic, bag_detail::RecordTime(scan.t_end_ns), msg);
  }

  Status WriteImu(const std::string& topic, const std::string& frame_id,
                  const ImuSample& sample) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckStamp(sample.t_ns, "IMU stamp"); !s.ok()) return s;
    sensor_msgs::Imu msg;
    msg.header.stamp.fromNSec(static_cast<uint64_t>(sample.t_ns));
    msg.header.frame_id = frame_id;
    msg.orientation.w = 1.0;
    msg.orientation_covariance[0] = -1.0;  // no orientation estimate
    msg.angular_velocity.x = sample.gyro_imu.x();
    msg.angular_velocity.y = sample.gyro_imu.y();
    msg.angular_velocity.z = sample.gyro_imu.z();
    msg.linear_acceleration.x = sample.acc_imu.x();
    msg.linear_acceleration.y = sample.acc_imu.y();
    msg.linear_acceleration.z = sample.acc_imu.z();
    return Write(topic, bag_detail::RecordTime(sample.t_ns), msg);
  }

  Status Close() override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    open_ = false;
    if (std::string why; !CloseBag(&why)) {
      std::remove(tmp_.c_str());
      return Status::InvalidInput("cannot write bag '" + path_ + "' (" + why + ")");
    }
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      std::remove(tmp_.c_str());
      return Status::InvalidInput("cannot rename '" + tmp_ + "' to '" + path_ + "': " + why);
    }
    return Status::Ok();
  }

 private:
  template <typename Msg>
  Status Write(const std::string& topic, const ros::Time& time, const Msg& msg) {
    try {
      bag_->write(topic, time, msg);
    } catch (const std::exception& e) {
      return Status::InvalidInput("cannot write bag '" + path_ + "' (" + e.what() + ")");
    }
    return Status::Ok();
  }

  // Closes the bag. When that fails (disk full, file-size limit) the
  // rosbag::Bag is abandoned rather than destroyed: its destructor retries the
  // failed write and throws from a destructor, which terminates the process.
  // Its file is closed when the process exits; the caller removes it.
  bool CloseBag(std::string* why) {
    try {
      bag_->close();
      bag_.reset();
      return true;
    } catch (const std::exception& e) {
      *why = e.what();
      (void)bag_.release();
      return false;
    }
  }

  std::string path_, tmp_;
  std::unique_ptr<rosbag::Bag> bag_;
  bool open_ = false;
};

}  // namespace

StatusOr<std::unique_ptr<SensorBagWriter>> SensorBagWriter::Create(const std::string& path) {
  auto writer = std::make_unique<RosbagSensorWriter>(path);
  if (Status s = writer->Init(); !s.ok()) return s;
  return std::unique_ptr<SensorBagWriter>(std::move(writer));
}

}  // namespace rvlio
