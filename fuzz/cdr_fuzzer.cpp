// libFuzzer target: the CDR decoders of ROS 2 messages (formats/cdr.h) on
// arbitrary payloads, as the ROS 2 sensor reader calls them.
//
// Input layout: byte 0 picks the message (0 sensor_msgs/msg/PointCloud2, then
// DecodePointCloud2 with lidar.type auto as the reader does; 1
// sensor_msgs/msg/Imu; 2 livox_ros_driver2/msg/CustomMsg, then
// DecodeLivoxCustomMsg; 3
// std_msgs/msg/String; 4 nav_msgs/msg/Odometry and 5 tf2_msgs/msg/TFMessage,
// what `rvlio live` publishes), the rest is the CDR payload (encapsulation
// header first). Seeds (fuzz/corpus/cdr/) are real payloads: the first cloud and IMU
// message of a small `rvlio simulate --format db3` sequence, big-endian
// re-encodings of them, a talker String of test/data/ros2_bags, a CustomMsg,
// and an Odometry and a TFMessage as `rvlio live` publishes them.
//
// Invariants: a failure is InvalidInput with a message; a decoded message
// re-encodes (little endian) to a payload that decodes to the same values;
// a cloud's data lies inside the payload.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "rvlio/formats/cdr.h"
#include "rvlio/formats/livox.h"

namespace {

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "cdr fuzzer invariant violated: %s\n", what);
  std::abort();
}
void Require(bool ok, const char* what) {
  if (!ok) Fail(what);
}

template <typename T>
bool CheckError(const rvlio::StatusOr<T>& r) {
  if (r.ok()) return true;
  Require(r.status().code() == rvlio::StatusCode::kInvalidInput, "error is not InvalidInput");
  Require(!r.status().message().empty(), "empty error message");
  return false;
}

void FuzzCloud(const uint8_t* data, size_t size) {
  const rvlio::StatusOr<rvlio::PointCloud2View> cloud = rvlio::cdr::DecodePointCloud2(data, size, "/f");
  if (!CheckError(cloud)) return;
  Require(cloud->data_size == 0 ||
              (cloud->data >= data && cloud->data + cloud->data_size <= data + size),
          "cloud data outside the payload");
  const std::vector<uint8_t> again = rvlio::cdr::EncodePointCloud2(*cloud, "f", false);
  const auto back = rvlio::cdr::DecodePointCloud2(again.data(), again.size(), "/f");
  Require(back.ok() && back->header_stamp_ns == cloud->header_stamp_ns &&
              back->width == cloud->width && back->height == cloud->height &&
              back->fields.size() == cloud->fields.size() &&
              back->data_size == cloud->data_size && back->row_step == cloud->row_step,
          "PointCloud2 round trip differs");
  rvlio::LidarOptions lidar;
  rvlio::DecodeStats stats;
  const rvlio::StatusOr<rvlio::Scan> scan = rvlio::DecodePointCloud2(*cloud, lidar, &stats);
  if (!CheckError(scan)) return;
  Require(static_cast<int64_t>(scan->points.size()) <= stats.raw_points, "more points than raw");
  Require(scan->t_start_ns <= scan->t_end_ns, "t_start > t_end");
}

void FuzzImu(const uint8_t* data, size_t size) {
  const auto imu = rvlio::cdr::DecodeImu(data, size, "/f");
  if (!CheckError(imu)) return;
  const std::vector<uint8_t> again = rvlio::cdr::EncodeImu(*imu);
  const auto back = rvlio::cdr::DecodeImu(again.data(), again.size(), "/f");
  // Compare bit patterns: NaN payloads must survive too.
  Require(back.ok() && back->header_stamp_ns == imu->header_stamp_ns &&
              back->frame_id == imu->frame_id &&
              std::memcmp(back->linear_acceleration.data(), imu->linear_acceleration.data(), 24) == 0 &&
              std::memcmp(back->angular_velocity.data(), imu->angular_velocity.data(), 24) == 0,
          "Imu round trip differs");
}

void FuzzLivox(const uint8_t* data, size_t size) {
  const auto msg = rvlio::cdr::DecodeLivoxCustomMsg(data, size, "/f");
  if (!CheckError(msg)) return;
  const std::vector<uint8_t> again = rvlio::cdr::EncodeLivoxCustomMsg(*msg);
  const auto back = rvlio::cdr::DecodeLivoxCustomMsg(again.data(), again.size(), "/f");
  Require(back.ok() && back->timebase == msg->timebase && back->point_num == msg->point_num &&
              back->points.size() == msg->points.size() && back->frame_id == msg->frame_id,
          "CustomMsg round trip differs");
  for (size_t i = 0; i < msg->points.size(); ++i)
    Require(back->points[i].offset_time == msg->points[i].offset_time &&
                back->points[i].line == msg->points[i].line,
            "CustomMsg point round trip differs");  // Then as the reader does: the CustomMsg -> Scan conversion.
  rvlio::LidarOptions lidar;
  rvlio::DecodeStats stats;
  const rvlio::StatusOr<rvlio::Scan> scan = rvlio::DecodeLivoxCustomMsg(*msg, lidar, &stats);
  if (!CheckError(scan)) return;
  Require(scan->points.size() <= msg->points.size(), "more points than the message");
  Require(scan->t_start_ns <= scan->t_end_ns, "t_start > t_end");
}

void FuzzString(const uint8_t* data, size_t size) {
  const auto text = rvlio::cdr::DecodeString(data, size, "/f");
  if (!CheckError(text)) return;
  const std::vector<uint8_t> again = rvlio::cdr::EncodeString(*text);
  const auto back = rvlio::cdr::DecodeString(again.data(), again.size(), "/f");
  Require(back.ok() && *back == *text, "String round trip differs");
}

void FuzzOdometry(const uint8_t* data, size_t size) {
  const auto odo = rvlio::cdr::DecodeOdometry(data, size, "/f");
  if (!CheckError(odo)) return;
  const std::vector<uint8_t> again = rvlio::cdr::EncodeOdometry(*odo);
  const auto back = rvlio::cdr::DecodeOdometry(again.data(), again.size(), "/f");
  Require(back.ok() && back->stamp_ns == odo->stamp_ns && back->frame_id == odo->frame_id &&
              back->child_frame_id == odo->child_frame_id &&
              std::memcmp(back->pose_covariance.data(), odo->pose_covariance.data(), 36 * 8) == 0,
          "Odometry round trip differs");
}

void FuzzTf(const uint8_t* data, size_t size) {
  const auto tf = rvlio::cdr::DecodeTfMessage(data, size, "/f");
  if (!CheckError(tf)) return;
  const std::vector<uint8_t> again = rvlio::cdr::EncodeTfMessage(*tf);
  const auto back = rvlio::cdr::DecodeTfMessage(again.data(), again.size(), "/f");
  Require(back.ok() && back->size() == tf->size(), "TFMessage round trip differs");
  for (size_t i = 0; i < tf->size(); ++i)
    Require((*back)[i].child_frame_id == (*tf)[i].child_frame_id &&
                (*back)[i].stamp_ns == (*tf)[i].stamp_ns,
            "TFMessage transform round trip differs");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  // An exact-size copy, so that ASan sees any read past the payload.
  const std::vector<uint8_t> payload(data + 1, data + size);
  const uint8_t* p = payload.empty() ? nullptr : payload.data();
  switch (data[0] % 6) {
    case 0: FuzzCloud(p, payload.size()); break;
    case 1: FuzzImu(p, payload.size()); break;
    case 2: FuzzLivox(p, payload.size()); break;
    case 3: FuzzString(p, payload.size()); break;
    case 4: FuzzOdometry(p, payload.size()); break;
    default: FuzzTf(p, payload.size()); break;
  }
  return 0;
}
