#pragma once
// Test helper: raw PointCloud2 payloads in the layouts of common LiDAR
// drivers, built byte by byte (no ROS types), so that the decoder and the bag
// reader can be checked against values the test chose.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "rvlio/formats/pointcloud2.h"

namespace rvlio::test {

struct RawCloud {
  TimeNs stamp_ns = 0;
  uint32_t height = 1, width = 0, point_step = 0, row_step = 0;
  bool is_bigendian = false;
  std::vector<PointField> fields;
  std::vector<uint8_t> data;
  std::string time_field;  // name of the per-point time field ("" for none)
  std::string ring_field;  // "ring", "line" or ""

  PointCloud2View View(const std::string& topic = "/cloud") const {
    PointCloud2View v;
    v.header_stamp_ns = stamp_ns;
    v.height = height;
    v.width = width;
    v.point_step = point_step;
    v.row_step = row_step;
    v.is_bigendian = is_bigendian;
    v.fields = fields;
    v.data = data.data();
    v.data_size = data.size();
    v.topic = topic;
    return v;
  }

  // width x height points, `pad` spare bytes at the end of every row.
  void Resize(uint32_t w, uint32_t h = 1, uint32_t pad = 0) {
    width = w;
    height = h;
    row_step = point_step * w + pad;
    data.assign(size_t{row_step} * h, 0xAB);  // padding bytes are garbage on purpose
    for (uint32_t i = 0; i < w * h; ++i) ZeroPoint(i);
  }

  bool Has(const std::string& name) const {
    return std::any_of(fields.begin(), fields.end(),
                       [&](const PointField& f) { return f.name == name; });
  }

  // Writes `v` into field `name` of point i (row-major), in the field's type.
  void Set(uint32_t i, const std::string& name, double v) {
    const PointField* f = nullptr;
    for (const auto& g : fields)
      if (g.name == name) f = &g;
    if (!f) throw std::runtime_error("no field " + name);
    uint8_t* p = data.data() + size_t{i / width} * row_step + size_t{i % width} * point_step + f->offset;
    switch (f->datatype) {
      case kPointInt8: Store<int8_t>(p, v); break;
      case kPointUint8: Store<uint8_t>(p, v); break;
      case kPointInt16: Store<int16_t>(p, v); break;
      case kPointUint16: Store<uint16_t>(p, v); break;
      case kPointInt32: Store<int32_t>(p, v); break;
      case kPointUint32: Store<uint32_t>(p, v); break;
      case kPointFloat32: Store<float>(p, v); break;
      case kPointFloat64: Store<double>(p, v); break;
      default: throw std::runtime_error("bad datatype");
    }
  }

  void SetPoint(uint32_t i, double x, double y, double z, double intensity, double time,
                int ring) {
    Set(i, "x", x);
    Set(i, "y", y);
    Set(i, "z", z);
    if (Has("intensity")) Set(i, "intensity", intensity);
    if (Has("reflectivity")) Set(i, "reflectivity", intensity);  // Ouster: what rvlio reads
    if (!time_field.empty()) Set(i, time_field, time);
    if (!ring_field.empty()) Set(i, ring_field, ring);
  }

 private:
  void ZeroPoint(uint32_t i) {
    std::memset(data.data() + size_t{i / width} * row_step + size_t{i % width} * point_step, 0,
                point_step);
  }
  template <typename T>
  void Store(uint8_t* p, double v) {
    // An integer field saturates, as a driver's would (a value beyond the
    // type's range has no conversion: undefined behaviour).
    if constexpr (std::is_integral_v<T>)
      v = std::clamp(v, static_cast<double>(std::numeric_limits<T>::lowest()),
                     static_cast<double>(std::numeric_limits<T>::max()));
    const T value = static_cast<T>(v);
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    if (is_bigendian) std::reverse(bytes, bytes + sizeof(T));
    std::memcpy(p, bytes, sizeof(T));
  }
};

inline RawCloud MakeCloud(std::vector<PointField> fields, uint32_t point_step,
                          std::string time_field, std::string ring_field) {
  RawCloud c;
  c.fields = std::move(fields);
  c.point_step = point_step;
  c.time_field = std::move(time_field);
  c.ring_field = std::move(ring_field);
  return c;
}

// ouster_ros: t uint32 ns from the scan start.
inline RawCloud OusterCloud() {
  return MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                    {"z", 8, kPointFloat32, 1}, {"intensity", 16, kPointFloat32, 1},
                    {"t", 20, kPointUint32, 1}, {"reflectivity", 24, kPointUint16, 1},
                    {"ring", 26, kPointUint16, 1}, {"ambient", 28, kPointUint16, 1},
                    {"range", 32, kPointUint32, 1}},
                   48, "t", "ring");
}
// velodyne_pointcloud PointXYZIRT: time float32 s relative to the stamp.
inline RawCloud VelodyneCloud() {
  return MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                    {"z", 8, kPointFloat32, 1}, {"intensity", 16, kPointFloat32, 1},
                    {"ring", 20, kPointUint16, 1}, {"time", 24, kPointFloat32, 1}},
                   32, "time", "ring");
}
// hesai_lidar: timestamp float64 absolute s.
inline RawCloud HesaiCloud() {
  return MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                    {"z", 8, kPointFloat32, 1}, {"intensity", 16, kPointFloat32, 1},
                    {"timestamp", 24, kPointFloat64, 1}, {"ring", 32, kPointUint16, 1}},
                   48, "timestamp", "ring");
}
// livox_ros_driver2 PointXYZRTLT: timestamp float64 absolute (ns or s), line.
inline RawCloud LivoxCloud() {
  return MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                    {"z", 8, kPointFloat32, 1}, {"intensity", 12, kPointFloat32, 1},
                    {"tag", 16, kPointUint8, 1}, {"line", 17, kPointUint8, 1},
                    {"timestamp", 18, kPointFloat64, 1}},
                   26, "timestamp", "line");
}
// A Livox conversion that keeps the driver's relative offset_time (ns).
inline RawCloud LivoxOffsetCloud() {
  return MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                    {"z", 8, kPointFloat32, 1}, {"intensity", 12, kPointFloat32, 1},
                    {"offset_time", 16, kPointUint32, 1}, {"line", 20, kPointUint8, 1}},
                   24, "offset_time", "line");
}

}  // namespace rvlio::test
