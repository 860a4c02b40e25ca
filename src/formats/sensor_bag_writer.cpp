// SensorBagWriter: ROS1 messages through rosbag::Bag, written to path + ".tmp"
// and renamed into place on Close().
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <memory>

#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/NavSatFix.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>
#include <std_msgs/String.h>

#include "ros1_raw_message.h"
#include "rosbag_common.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/sensor_bag.h"
#include "sensor_writer_common.h"

namespace rvlio {
namespace {

// Largest time a ROS1 stamp (uint32 seconds) can hold.
constexpr TimeNs kMaxRosNs = static_cast<TimeNs>(std::numeric_limits<uint32_t>::max()) * kNsPerSecond;

Status CheckRosStamp(TimeNs t_ns, const std::string& what) {
  return bag_detail::CheckStamp(t_ns, kMaxRosNs, "ROS1 time range [0, 2^32 s)", what);
}

void ToRosCloud(const bag_detail::OwnedCloud& cloud, sensor_msgs::PointCloud2* msg) {
  const PointCloud2View& v = cloud.view;
  msg->height = v.height;
  msg->width = v.width;
  msg->is_bigendian = v.is_bigendian;
  msg->is_dense = cloud.is_dense;
  msg->point_step = v.point_step;
  msg->row_step = v.row_step;
  for (const PointField& f : v.fields) {
    sensor_msgs::PointField field;
    field.name = f.name;
    field.offset = f.offset;
    field.datatype = f.datatype;
    field.count = f.count;
    msg->fields.push_back(field);
  }
  msg->data = cloud.data;
}

class RosbagSensorWriter final : public SensorBagWriter {
 public:
  explicit RosbagSensorWriter(std::string path)
      : path_(std::move(path)), target_(path_), tmp_(path_ + ".tmp") {}
  ~RosbagSensorWriter() override {
    if (!open_) return;
    std::string why;
    (void)CloseBag(&why);
    std::remove(tmp_.c_str());
  }

  Status Init() {
    // The file replaced: the path or a link's final target (never a FIFO or a device).
    StatusOr<std::string> target = ResolveOutputFile(path_);
    if (!target.ok()) return target.status();
    target_ = *target;
    tmp_ = target_ + ".tmp";
    bag_ = std::make_unique<rosbag::Bag>();
    try {
      bag_->open(tmp_, rosbag::bagmode::Write);
    } catch (const std::exception& e) {
      std::string ignored;
      (void)CloseBag(&ignored);  // a half-opened Bag may still hold the file
      std::remove(tmp_.c_str());
      return Status::IoError("cannot write bag '" + tmp_ + "' (" + e.what() + ")");
    }
    open_ = true;
    return Status::Ok();
  }

  Status WriteOusterScan(const std::string& topic, const std::string& frame_id, const Scan& scan,
                         int rows, int cols) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckRosStamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    bag_detail::OwnedCloud cloud;
    if (Status s = bag_detail::BuildOusterCloud(scan, rows, cols, &cloud); !s.ok()) return s;
    sensor_msgs::PointCloud2 msg;
    msg.header.stamp.fromNSec(static_cast<uint64_t>(scan.t_start_ns));
    msg.header.frame_id = frame_id;
    ToRosCloud(cloud, &msg);
    // Recorded when the driver publishes it: at the end of the sweep.
    return Write(topic, bag_detail::RecordTime(scan.t_end_ns), msg);
  }

  Status WriteLivoxScan(const std::string& topic, const std::string& frame_id,
                        const Scan& scan) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckRosStamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    // offset_time must fit uint32 ns after the timebase.
    if (Status s = bag_detail::CheckRelativePointTimes(scan); !s.ok()) return s;
    bag_detail::LivoxRos1Bytes msg{SerializeLivoxRos1(ScanToLivoxCustomMsg(scan, frame_id))};
    // Recorded when the driver publishes it: at the end of the sweep.
    return Write(topic, bag_detail::RecordTime(scan.t_end_ns), msg);
  }

  Status WriteImu(const std::string& topic, const std::string& frame_id,
                  const ImuSample& sample) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(sample.t_ns, "IMU stamp"); !s.ok()) return s;
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

  Status WriteNavSatFix(const std::string& topic, const NavSatFix& fix) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(fix.header_stamp_ns, "NavSatFix stamp"); !s.ok()) return s;
    sensor_msgs::NavSatFix msg;
    msg.header.stamp.fromNSec(static_cast<uint64_t>(fix.header_stamp_ns));
    msg.header.frame_id = fix.frame_id;
    msg.status.status = fix.status;
    msg.status.service = fix.service;
    msg.latitude = fix.latitude_deg;
    msg.longitude = fix.longitude_deg;
    msg.altitude = fix.altitude_m;
    for (int i = 0; i < 9; ++i) msg.position_covariance[i] = fix.position_covariance[i];
    msg.position_covariance_type = fix.covariance_type;
    return Write(topic, bag_detail::RecordTime(fix.header_stamp_ns), msg);
  }

  Status WriteOusterPacket(const std::string& topic, TimeNs receive_ns,
                           const std::vector<uint8_t>& packet) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(receive_ns, "packet receive time"); !s.ok()) return s;
    bag_detail::OusterPacketRos1Bytes msg;
    msg.bytes.resize(4 + packet.size());  // uint8[] buf: uint32 length + bytes
    const uint32_t n = static_cast<uint32_t>(packet.size());
    for (int i = 0; i < 4; ++i) msg.bytes[i] = static_cast<uint8_t>(n >> (8 * i));
    std::copy(packet.begin(), packet.end(), msg.bytes.begin() + 4);
    return Write(topic, bag_detail::RecordTime(receive_ns), msg);
  }

  Status WriteString(const std::string& topic, TimeNs receive_ns, const std::string& text) override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    if (Status s = CheckRosStamp(receive_ns, "String receive time"); !s.ok()) return s;
    std_msgs::String msg;
    msg.data = text;
    return Write(topic, bag_detail::RecordTime(receive_ns), msg);
  }

  Status Close() override {
    if (!open_) return Status::Internal("bag '" + path_ + "' is already closed");
    open_ = false;
    if (std::string why; !CloseBag(&why)) {
      std::remove(tmp_.c_str());
      return Status::IoError("cannot write bag '" + path_ + "' (" + why + ")");
    }
    if (std::rename(tmp_.c_str(), target_.c_str()) != 0) {
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
      return Status::IoError("cannot write bag '" + path_ + "' (" + e.what() + ")");
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

  std::string path_, target_, tmp_;
  std::unique_ptr<rosbag::Bag> bag_;
  bool open_ = false;
};

}  // namespace

StatusOr<std::unique_ptr<SensorBagWriter>> SensorBagWriter::Create(const std::string& path,
                                                                   const BagWriterOptions& options) {
  if (options.format == "mcap" || options.format == "db3")
    return bag_detail::CreateRos2Writer(path, options);
  if (options.format != "ros1")
    return Status::InvalidInput("bag format '" + options.format +
                                "' is not one of ros1, mcap, db3");
  auto writer = std::make_unique<RosbagSensorWriter>(path);
  if (Status s = writer->Init(); !s.ok()) return s;
  return std::unique_ptr<SensorBagWriter>(std::move(writer));
}

}  // namespace rvlio
