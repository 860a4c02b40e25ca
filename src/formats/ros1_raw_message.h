#pragma once
// Private (src/formats only): serialized ROS1 messages for rosbag without the
// drivers' generated headers. Ros1RawBytes<Type> holds a message's wire bytes;
// these traits tell rosbag its type, md5 and definition (from Type) and copy
// the bytes. Two types: livox_ros_driver/CustomMsg (the bytes of
// formats/livox.h, SerializeLivoxRos1 / ParseLivoxRos1) and
// ouster_ros/PacketMsg (uint8[] buf).
#include <cstdint>
#include <cstring>
#include <vector>

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <rosbag/message_instance.h>

#include "rvlio/formats/livox.h"

namespace rvlio::bag_detail {

template <typename Type>
struct Ros1RawBytes {
  std::vector<uint8_t> bytes;
};

struct LivoxRos1Message {
  static const char* type() { return kLivoxRos1Type; }
  static const char* md5() { return kLivoxRos1Md5; }
  static const char* definition() { return kLivoxRos1Definition; }
};
using LivoxRos1Bytes = Ros1RawBytes<LivoxRos1Message>;

// ouster_ros/PacketMsg: md5 of its one-line definition, as the driver's bags carry it.
struct OusterPacketRos1Message {
  static const char* type() { return "ouster_ros/PacketMsg"; }
  static const char* md5() { return "4f7b5949e76f86d01e96b0e33ba9b5e3"; }
  static const char* definition() { return "uint8[] buf\n"; }
};
using OusterPacketRos1Bytes = Ros1RawBytes<OusterPacketRos1Message>;

}  // namespace rvlio::bag_detail

namespace ros {
namespace message_traits {
template <typename T>
struct IsMessage<rvlio::bag_detail::Ros1RawBytes<T>> : TrueType {};
template <typename T>
struct MD5Sum<rvlio::bag_detail::Ros1RawBytes<T>> {
  static const char* value() { return T::md5(); }
  static const char* value(const rvlio::bag_detail::Ros1RawBytes<T>&) { return value(); }
};
template <typename T>
struct DataType<rvlio::bag_detail::Ros1RawBytes<T>> {
  static const char* value() { return T::type(); }
  static const char* value(const rvlio::bag_detail::Ros1RawBytes<T>&) { return value(); }
};
template <typename T>
struct Definition<rvlio::bag_detail::Ros1RawBytes<T>> {
  static const char* value() { return T::definition(); }
  static const char* value(const rvlio::bag_detail::Ros1RawBytes<T>&) { return value(); }
};
}  // namespace message_traits

namespace serialization {
template <typename T>
struct Serializer<rvlio::bag_detail::Ros1RawBytes<T>> {
  template <typename Stream>
  inline static void write(Stream& stream, const rvlio::bag_detail::Ros1RawBytes<T>& m) {
    if (!m.bytes.empty())
      std::memcpy(stream.advance(static_cast<uint32_t>(m.bytes.size())), m.bytes.data(),
                  m.bytes.size());
  }
  inline static uint32_t serializedLength(const rvlio::bag_detail::Ros1RawBytes<T>& m) {
    return static_cast<uint32_t>(m.bytes.size());
  }
};
}  // namespace serialization
}  // namespace ros
