#include "ros1_messages.h"

#include <vector>

#include "ros1_wire.h"

namespace rvlio::bag_detail {
namespace {

Status TooShort(const std::string& where, const char* type, size_t size, const char* part) {
  return Status::InvalidInput(where + ": " + type + " message of " + std::to_string(size) +
                              " bytes ends inside its " + part);
}

bool ReadField(Ros1WireReader& r, PointField* f) {
  return r.ReadString(&f->name) && r.Read(&f->offset) && r.Read(&f->datatype) &&
         r.Read(&f->count);
}

bool ReadVector3(Ros1WireReader& r, std::array<double, 3>* v) {
  return r.Read(&(*v)[0]) && r.Read(&(*v)[1]) && r.Read(&(*v)[2]);
}

// float64[n] fixed array (no length prefix in ROS1), skipped.
bool SkipDoubles(Ros1WireReader& r, int n) {
  double unused = 0.0;
  for (int i = 0; i < n; ++i)
    if (!r.Read(&unused)) return false;
  return true;
}

}  // namespace

StatusOr<PointCloud2View> ParseRos1PointCloud2(const uint8_t* data, size_t size,
                                               const std::string& topic, const std::string& where) {
  constexpr const char* kType = "sensor_msgs/PointCloud2";
  Ros1WireReader r(data, size);
  PointCloud2View v;
  std::string frame_id;
  uint32_t field_count = 0;
  if (!r.ReadHeader(&v.header_stamp_ns, &frame_id) || !r.Read(&v.height) || !r.Read(&v.width) ||
      !r.Read(&field_count))
    return TooShort(where, kType, size, "header");
  // Each field takes at least 13 bytes (empty name, offset, datatype, count).
  if (field_count > r.remaining() / 13) return TooShort(where, kType, size, "fields");
  v.fields.resize(field_count);
  for (PointField& f : v.fields)
    if (!ReadField(r, &f)) return TooShort(where, kType, size, "fields");
  uint8_t is_bigendian = 0, is_dense = 0;
  if (!r.Read(&is_bigendian) || !r.Read(&v.point_step) || !r.Read(&v.row_step) ||
      !r.ReadBytes(&v.data, &v.data_size) || !r.Read(&is_dense))
    return TooShort(where, kType, size, "data");
  v.is_bigendian = is_bigendian != 0;
  v.topic = topic;
  return v;
}

StatusOr<Ros1Imu> ParseRos1Imu(const uint8_t* data, size_t size, const std::string& where) {
  constexpr const char* kType = "sensor_msgs/Imu";
  Ros1WireReader r(data, size);
  Ros1Imu imu;
  std::string frame_id;
  if (!r.ReadHeader(&imu.header_stamp_ns, &frame_id)) return TooShort(where, kType, size, "header");
  // orientation (x, y, z, w) and its covariance, then each vector and its
  // covariance.
  if (!SkipDoubles(r, 4 + 9) || !ReadVector3(r, &imu.angular_velocity) || !SkipDoubles(r, 9) ||
      !ReadVector3(r, &imu.linear_acceleration) || !SkipDoubles(r, 9))
    return TooShort(where, kType, size, "fields");
  return imu;
}

}  // namespace rvlio::bag_detail
