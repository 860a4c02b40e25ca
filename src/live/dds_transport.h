#pragma once
// Private (src/live): the ROS 2 transport on Cyclone DDS (dds_transport.cpp),
// with raw writers of any ROS 2 type for tools and tests (the ROS 2 player
// of test/live publishes recorded CDR messages through it).
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <dds/dds.h>

#include "transport.h"

namespace rvlio::live_detail {

// ROS 2's names on DDS: "/a/b" -> "rt/a/b"; "pkg/msg/T" <-> "pkg::msg::dds_::T_".
std::string DdsTopicName(const std::string& ros_topic);
std::string DdsTypeName(const std::string& ros_type);
std::string RosTypeName(const std::string& dds_type);

class DdsTransport final : public Transport {
 public:
  ~DdsTransport() override;
  // A participant in `domain_id` with ROS 2's USER_DATA.
  Status Init(int domain_id);

  WireEncoding encoding() const override { return WireEncoding::kCdr; }
  std::string origin() const override;
  Status Subscribe(const std::string& topic, int depth, MessageCallback callback) override;
  Status Advertise(const OutputTopics& topics) override;
  void Publish(OdometryTopic which, const OdometryMessage& msg) override;
  void PublishTf(const TransformMessage& msg) override;
  void Publish(CloudTopic which, const PointCloud2View& cloud, const std::string& frame_id) override;
  void Publish(const PathMessage& msg) override;
  void Publish(const DiagnosticMessage& msg) override;
  void Shutdown() override;
  void Flush() override;

  // A writer of `ros_type` ("sensor_msgs/msg/Imu") on `topic`: reliable, keep
  // last 10 (ROS 2's default) or best effort, keep last 5 (sensor data).
  Status AdvertiseRaw(const std::string& topic, const std::string& ros_type, bool reliable);
  // A CDR payload (encapsulation header included) on an advertised topic.
  void PublishRaw(const std::string& topic, const std::vector<uint8_t>& bytes);
  // Readers of rvlio's DDS writers of `topic` discovered so far (0 before any).
  int MatchedReaders(const std::string& topic) const;

 private:
  struct Writer {
    dds_entity_t entity = 0;
    const struct ddsi_sertype* type = nullptr;
  };
  // The type and reliability of the first discovered writer of `topic`.
  struct Offered {
    std::string dds_type;
    bool reliable = false;
  };
  std::optional<Offered> DiscoveredWriter(const std::string& topic);
  void Receive(const std::string& topic, int depth, const MessageCallback& callback);

  int domain_id_ = 0;
  dds_entity_t participant_ = 0, publications_ = 0;
  std::mutex discovery_mutex_;
  std::map<std::string, Offered> discovered_;  // by DDS topic
  std::map<std::string, Writer> writers_;          // by ROS topic
  std::unique_ptr<OutputTopics> topics_;
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

}  // namespace rvlio::live_detail
