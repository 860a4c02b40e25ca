#pragma once
// Private (src/live): a Cyclone DDS type whose samples are serialized CDR
// payloads, encapsulation header included, taken and written as bytes. The
// project's own CDR code (formats/cdr.h) decodes and encodes them, so there
// is one CDR implementation and no generated type support: the type is
// known to DDS only by its name (e.g. "sensor_msgs::msg::dds_::Imu_"),
// which is what DDS matches readers and writers on when neither side sends
// XTypes type information. Keyless (as every ROS 2 message type).
#include <cstdint>
#include <string>
#include <vector>

struct ddsi_sertype;
struct ddsi_serdata;

namespace rvlio::live_detail {

// A new sertype named `dds_type_name`; dds_create_topic_sertype takes it over.
ddsi_sertype* NewRawCdrType(const std::string& dds_type_name);

// A serdata holding `bytes` (a CDR payload with its 4-byte encapsulation
// header) of `type`, for dds_writecdr (which takes the reference).
ddsi_serdata* NewRawCdrSample(const ddsi_sertype* type, const std::vector<uint8_t>& bytes);

// The payload of a sample taken from a reader of a raw CDR topic.
const std::vector<uint8_t>& RawCdrBytes(const ddsi_serdata* sample);

}  // namespace rvlio::live_detail
