#pragma once
// Private (src/formats only): livox_ros_driver/CustomMsg as a ROS1 message for
// rosbag, without the driver's generated headers. The payload is the wire
// bytes of formats/livox.h (SerializeLivoxRos1 / ParseLivoxRos1); these traits
// tell rosbag its type, md5 and definition and copy the bytes.
#include <cstdint>
#include <cstring>
#include <vector>

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <rosbag/message_instance.h>

#include "rvlio/formats/livox.h"

namespace rvlio::bag_detail {

struct LivoxRos1Bytes {
  std::vector<uint8_t> bytes;
};

}  // namespace rvlio::bag_detail

namespace ros {
namespace message_traits {
template <>
struct IsMessage<rvlio::bag_detail::LivoxRos1Bytes> : TrueType {};
template <>
struct MD5Sum<rvlio::bag_detail::LivoxRos1Bytes> {
  static const char* value() { return rvlio::kLivoxRos1Md5; }
  static const char* value(const rvlio::bag_detail::LivoxRos1Bytes&) { return value(); }
};
template <>
struct DataType<rvlio::bag_detail::LivoxRos1Bytes> {
  static const char* value() { return rvlio::kLivoxRos1Type; }
  static const char* value(const rvlio::bag_detail::LivoxRos1Bytes&) { return value(); }
};
template <>
struct Definition<rvlio::bag_detail::LivoxRos1Bytes> {
  static const char* value() { return rvlio::kLivoxRos1Definition; }
  static const char* value(const rvlio::bag_detail::LivoxRos1Bytes&) { return value(); }
};
}  // namespace message_traits

namespace serialization {
template <>
struct Serializer<rvlio::bag_detail::LivoxRos1Bytes> {
  template <typename Stream>
  inline static void write(Stream& stream, const rvlio::bag_detail::LivoxRos1Bytes& m) {
    if (!m.bytes.empty())
      std::memcpy(stream.advance(static_cast<uint32_t>(m.bytes.size())), m.bytes.data(),
                  m.bytes.size());
  }
  inline static uint32_t serializedLength(const rvlio::bag_detail::LivoxRos1Bytes& m) {
    return static_cast<uint32_t>(m.bytes.size());
  }
};
}  // namespace serialization
}  // namespace ros
