#pragma once
// CDR (OMG CDR as ROS 2 writes it through Fast-CDR: XCDR1 / "plain" CDR),
// written from the specification, for the ROS 2 messages rvlio reads and
// writes. A payload is a 4-byte encapsulation header (0x00 0x00: big endian,
// 0x00 0x01: little endian; the two option bytes are ignored) followed by the
// fields, each aligned to its own size (1, 2, 4 or 8 bytes) relative to the
// first byte after the header. Strings are a uint32 length that counts the
// terminating NUL, then the bytes; sequences are a uint32 element count, then
// the elements; fixed arrays have no count.
//
// Decoders validate every length against the bytes left before they allocate
// or read: a corrupt payload is InvalidInput naming the message type and the
// field, never a crash or a huge allocation.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/nav_messages.h"
#include "rvlio/formats/pointcloud2.h"

namespace rvlio::cdr {

// ROS 2 type names.
inline constexpr const char* kPointCloud2Type = "sensor_msgs/msg/PointCloud2";
inline constexpr const char* kImuType = "sensor_msgs/msg/Imu";
inline constexpr const char* kStringType = "std_msgs/msg/String";
// livox_ros_driver2/msg/CustomMsg: kLivoxRos2Type (formats/livox.h).
// What `rvlio live` publishes (nav_messages.h).
inline constexpr const char* kOdometryType = "nav_msgs/msg/Odometry";
inline constexpr const char* kTfMessageType = "tf2_msgs/msg/TFMessage";
inline constexpr const char* kPathType = "nav_msgs/msg/Path";
inline constexpr const char* kDiagnosticArrayType = "diagnostic_msgs/msg/DiagnosticArray";

// The message definitions (ros2msg text, dependencies appended after
// "=====" separator lines as rosbag2 stores them), for MCAP schemas and the
// db3 message_definitions table.
const std::string& PointCloud2Definition();
const std::string& ImuDefinition();
const std::string& LivoxCustomMsgDefinition();
const std::string& NavSatFixDefinition();  // sensor_msgs/msg/NavSatFix (formats/navsatfix.h)

// Bounds-checked sequential reader of one CDR payload.
class Reader {
 public:
  // `what` names the message in errors (e.g. "sensor_msgs/msg/Imu on /imu").
  Reader(const uint8_t* data, size_t size, std::string what);
  // Reads the encapsulation header; must be called first.
  Status Begin();
  Status U8(uint8_t* v, const char* field);
  Status U16(uint16_t* v, const char* field);
  Status U32(uint32_t* v, const char* field);
  Status I32(int32_t* v, const char* field);
  Status U64(uint64_t* v, const char* field);
  Status F32(float* v, const char* field);
  Status F64(double* v, const char* field);
  Status Bool(bool* v, const char* field);
  Status String(std::string* v, const char* field);
  // A sequence count, checked against the bytes left (each element takes at
  // least `min_element_size` bytes).
  Status SequenceCount(uint32_t* count, size_t min_element_size, const char* field);
  // A uint8[] sequence, returned as a view into the payload.
  Status ByteSequence(const uint8_t** bytes, size_t* size, const char* field);
  // builtin_interfaces/Time stamp + frame_id.
  Status Header(TimeNs* stamp_ns, std::string* frame_id);
  size_t remaining() const { return size_ - pos_; }

 private:
  Status Align(size_t n, const char* field);
  Status Raw(void* out, size_t n, const char* field);
  Status Error(const char* field, const std::string& problem) const;

  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  size_t origin_ = 4;  // alignment origin: the first byte after the header
  bool swap_ = false;
  std::string what_;
};

// Little-endian CDR writer (what ROS 2 publishes on x86 and ARM).
class Writer {
 public:
  Writer();  // writes the encapsulation header 0x00 0x01 0x00 0x00
  void U8(uint8_t v);
  void U16(uint16_t v);
  void U32(uint32_t v);
  void I32(int32_t v);
  void U64(uint64_t v);
  void F32(float v);
  void F64(double v);
  void Bool(bool v) { U8(v ? 1 : 0); }
  void String(const std::string& v);
  void Bytes(const uint8_t* data, size_t size);  // a uint8[] sequence
  void Header(TimeNs stamp_ns, const std::string& frame_id);
  std::vector<uint8_t> Take() { return std::move(buffer_); }

 private:
  void Align(size_t n);
  void Raw(const void* data, size_t n);
  std::vector<uint8_t> buffer_;
};

// sensor_msgs/msg/Imu.
struct ImuMessage {
  TimeNs header_stamp_ns = 0;
  std::string frame_id;
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
  std::array<double, 9> orientation_covariance{};
  std::array<double, 3> angular_velocity{};
  std::array<double, 9> angular_velocity_covariance{};
  std::array<double, 3> linear_acceleration{};
  std::array<double, 9> linear_acceleration_covariance{};
};

// A PointCloud2 view into `data` (valid while the payload lives); the topic
// is copied into the view for DecodePointCloud2's messages.
StatusOr<PointCloud2View> DecodePointCloud2(const uint8_t* data, size_t size,
                                            const std::string& topic);
StatusOr<ImuMessage> DecodeImu(const uint8_t* data, size_t size, const std::string& topic);
StatusOr<LivoxCustomMsg> DecodeLivoxCustomMsg(const uint8_t* data, size_t size,
                                              const std::string& topic);
StatusOr<std::string> DecodeString(const uint8_t* data, size_t size, const std::string& topic);

// Encoders (little endian). PointCloud2 takes a view: its fields and data.
std::vector<uint8_t> EncodePointCloud2(const PointCloud2View& cloud, const std::string& frame_id,
                                       bool is_dense);
std::vector<uint8_t> EncodeImu(const ImuMessage& msg);
std::vector<uint8_t> EncodeLivoxCustomMsg(const LivoxCustomMsg& msg);
std::vector<uint8_t> EncodeString(const std::string& text);
std::vector<uint8_t> EncodeOdometry(const OdometryMessage& msg);
std::vector<uint8_t> EncodeTfMessage(const std::vector<TransformMessage>& transforms);
std::vector<uint8_t> EncodePath(const PathMessage& msg);
std::vector<uint8_t> EncodeDiagnosticArray(const DiagnosticMessage& msg);
// nav_msgs/msg/Odometry and tf2_msgs/msg/TFMessage, for subscribers (and tests).
StatusOr<OdometryMessage> DecodeOdometry(const uint8_t* data, size_t size, const std::string& topic);
StatusOr<std::vector<TransformMessage>> DecodeTfMessage(const uint8_t* data, size_t size,
                                                        const std::string& topic);

}  // namespace rvlio::cdr
