// The ROS 1 transport: roscpp (Debian's packages) with the master of
// ROS_MASTER_URI. Subscriptions take any type (topic_tools::ShapeShifter:
// the serialized bytes and the publisher's type name), each on a callback
// queue and thread of its own; the outputs are roscpp's message classes.
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>
#include <topic_tools/shape_shifter.h>

#include "rvlio/common/text.h"
#include "transport.h"

namespace rvlio::live_detail {
namespace {

ros::Time RosTime(TimeNs t_ns) { return ros::Time().fromNSec(static_cast<uint64_t>(std::max<TimeNs>(t_ns, 0))); }

std_msgs::Header Header(TimeNs t_ns, const std::string& frame_id) {
  std_msgs::Header h;
  h.stamp = RosTime(t_ns);
  h.frame_id = frame_id;
  return h;
}

geometry_msgs::Pose Pose(const PoseMessage& p) {
  geometry_msgs::Pose out;
  out.position.x = p.position[0], out.position.y = p.position[1], out.position.z = p.position[2];
  out.orientation.x = p.orientation_xyzw[0], out.orientation.y = p.orientation_xyzw[1];
  out.orientation.z = p.orientation_xyzw[2], out.orientation.w = p.orientation_xyzw[3];
  return out;
}

class Ros1Transport final : public Transport {
 public:
  explicit Ros1Transport(std::string master) : master_(std::move(master)) {}
  ~Ros1Transport() override {
    Shutdown();
    ros::shutdown();
  }

  WireEncoding encoding() const override { return WireEncoding::kRos1; }
  std::string origin() const override { return "ROS 1 master " + master_; }

  Status Subscribe(const std::string& topic, int depth, MessageCallback callback) override {
    auto queue = std::make_unique<ros::CallbackQueue>();
    ros::SubscribeOptions options;
    options.init<topic_tools::ShapeShifter>(
        topic, static_cast<uint32_t>(depth),
        [cb = std::move(callback)](const topic_tools::ShapeShifter::ConstPtr& msg) {
          std::vector<uint8_t> bytes(msg->size());
          ros::serialization::OStream stream(bytes.data(), static_cast<uint32_t>(bytes.size()));
          msg->write(stream);
          cb(bytes.data(), bytes.size(), msg->getDataType());
        });
    options.callback_queue = queue.get();
    options.transport_hints = ros::TransportHints().tcpNoDelay();
    subscribers_.push_back(node_.subscribe(options));
    ros::CallbackQueue* q = queue.get();
    queues_.push_back(std::move(queue));
    threads_.emplace_back([this, q] {
      while (!stop_) q->callAvailable(ros::WallDuration(0.02));
    });
    return Status::Ok();
  }

  Status Advertise(const OutputTopics& t) override {
    odometry_ = node_.advertise<nav_msgs::Odometry>(t.odometry, 10);
    odometry_imu_ = node_.advertise<nav_msgs::Odometry>(t.odometry_imu, 50);
    cloud_ = node_.advertise<sensor_msgs::PointCloud2>(t.cloud, 2);
    map_ = node_.advertise<sensor_msgs::PointCloud2>(t.map, 1, /*latch=*/true);
    path_ = node_.advertise<nav_msgs::Path>(t.path, 1);
    status_ = node_.advertise<diagnostic_msgs::DiagnosticArray>(t.status, 10);
    tf_ = node_.advertise<tf2_msgs::TFMessage>(t.tf, 100);
    return Status::Ok();
  }

  void Publish(OdometryTopic which, const OdometryMessage& m) override {
    nav_msgs::Odometry out;
    out.header = Header(m.stamp_ns, m.frame_id);
    out.child_frame_id = m.child_frame_id;
    out.pose.pose = Pose(m.pose);
    std::copy(m.pose_covariance.begin(), m.pose_covariance.end(), out.pose.covariance.begin());
    out.twist.twist.linear.x = m.linear_velocity[0];
    out.twist.twist.linear.y = m.linear_velocity[1];
    out.twist.twist.linear.z = m.linear_velocity[2];
    out.twist.twist.angular.x = m.angular_velocity[0];
    out.twist.twist.angular.y = m.angular_velocity[1];
    out.twist.twist.angular.z = m.angular_velocity[2];
    std::copy(m.twist_covariance.begin(), m.twist_covariance.end(), out.twist.covariance.begin());
    (which == OdometryTopic::kScanRate ? odometry_ : odometry_imu_).publish(out);
  }

  void PublishTf(const TransformMessage& m) override {
    tf2_msgs::TFMessage out;
    out.transforms.resize(1);
    geometry_msgs::TransformStamped& t = out.transforms[0];
    t.header = Header(m.stamp_ns, m.frame_id);
    t.child_frame_id = m.child_frame_id;
    t.transform.translation.x = m.translation[0];
    t.transform.translation.y = m.translation[1];
    t.transform.translation.z = m.translation[2];
    t.transform.rotation.x = m.rotation_xyzw[0];
    t.transform.rotation.y = m.rotation_xyzw[1];
    t.transform.rotation.z = m.rotation_xyzw[2];
    t.transform.rotation.w = m.rotation_xyzw[3];
    tf_.publish(out);
  }

  void Publish(CloudTopic which, const PointCloud2View& c, const std::string& frame_id) override {
    sensor_msgs::PointCloud2 out;
    out.header = Header(c.header_stamp_ns, frame_id);
    out.height = c.height, out.width = c.width;
    for (const PointField& f : c.fields) {
      sensor_msgs::PointField field;
      field.name = f.name, field.offset = f.offset, field.datatype = f.datatype, field.count = f.count;
      out.fields.push_back(field);
    }
    out.is_bigendian = c.is_bigendian;
    out.point_step = c.point_step, out.row_step = c.row_step;
    out.data.assign(c.data, c.data + c.data_size);
    out.is_dense = true;
    (which == CloudTopic::kMap ? map_ : cloud_).publish(out);
  }

  void Publish(const PathMessage& m) override {
    nav_msgs::Path out;
    out.header = Header(m.stamp_ns, m.frame_id);
    out.poses.resize(m.poses.size());
    for (size_t i = 0; i < m.poses.size(); ++i) {
      out.poses[i].header = Header(m.poses[i].first, m.frame_id);
      out.poses[i].pose = Pose(m.poses[i].second);
    }
    path_.publish(out);
  }

  void Publish(const DiagnosticMessage& m) override {
    diagnostic_msgs::DiagnosticArray out;
    out.header = Header(m.stamp_ns, "");
    diagnostic_msgs::DiagnosticStatus s;
    s.level = m.level, s.name = m.name, s.message = m.message, s.hardware_id = m.hardware_id;
    for (const auto& [k, v] : m.values) {
      diagnostic_msgs::KeyValue kv;
      kv.key = k, kv.value = v;
      s.values.push_back(kv);
    }
    out.status.push_back(s);
    status_.publish(out);
  }

  // roscpp has no call that waits for its outgoing queues: the messages of
  // the last results (published just before the end) get a moment to leave.
  void Flush() override { std::this_thread::sleep_for(std::chrono::milliseconds(200)); }

  void Shutdown() override {
    stop_ = true;
    for (std::thread& t : threads_)
      if (t.joinable()) t.join();
    threads_.clear();
    subscribers_.clear();
  }

 private:
  std::string master_;
  ros::NodeHandle node_;
  std::vector<std::unique_ptr<ros::CallbackQueue>> queues_;
  std::vector<ros::Subscriber> subscribers_;
  ros::Publisher odometry_, odometry_imu_, cloud_, map_, path_, status_, tf_;
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

// roscpp stops the process (ROS_BREAK) on a master URI it cannot split into
// host and port: "http://HOST:PORT[/]" is checked here first.
bool IsMasterUri(const std::string& uri) {
  const std::string scheme = "http://";
  if (uri.compare(0, scheme.size(), scheme) != 0) return false;
  std::string rest = uri.substr(scheme.size());
  if (!rest.empty() && rest.back() == '/') rest.pop_back();
  const size_t colon = rest.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 >= rest.size()) return false;
  if (rest.find('/') != std::string::npos) return false;
  long long port = 0;
  for (size_t i = colon + 1; i < rest.size(); ++i) {
    if (rest[i] < '0' || rest[i] > '9' || (port = port * 10 + (rest[i] - '0')) > 65535) return false;
  }
  return port > 0;
}

}  // namespace

StatusOr<std::unique_ptr<Transport>> ConnectRos1(const LiveOptions& live, const std::string& node_name,
                                                 const std::function<bool()>& stopped) {
  const char* uri = std::getenv("ROS_MASTER_URI");
  if (uri == nullptr || *uri == '\0')
    return Status::InvalidInput("--ros1: ROS_MASTER_URI is not set (e.g. http://localhost:11311)");
  const std::string master = uri;
  if (!IsMasterUri(master))
    return Status::InvalidInput("--ros1: ROS_MASTER_URI '" + master +
                                "' is not http://HOST:PORT");
  if (ros::isInitialized())
    return Status::Internal("--ros1: roscpp is already initialized in this process");
  ros::M_string remappings;
  ros::init(remappings, node_name,
            ros::init_options::NoSigintHandler | ros::init_options::AnonymousName);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(live.connect_timeout);
  while (!ros::master::check()) {
    if (stopped()) return std::unique_ptr<Transport>();
    if (std::chrono::steady_clock::now() >= deadline)
      return Status::InvalidInput("--ros1: the ROS master " + master +
                                  " (ROS_MASTER_URI) did not answer within live.connect_timeout " +
                                  FormatFixed(live.connect_timeout, 1) + " s");
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ros::start();
  return std::unique_ptr<Transport>(std::make_unique<Ros1Transport>(master));
}

}  // namespace rvlio::live_detail
