#pragma once
// Test helpers for bags generated at run time in a temporary folder.
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/PointCloud2.h>

#include "cloud_builder.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::test {

constexpr TimeNs kT0 = 1700000000000000000LL;  // a realistic epoch stamp
constexpr TimeNs kMs = 1000000;

class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = ::testing::TempDir() + "rvlio_bag_XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl.data()), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return dir_ + "/" + name; }
  std::string dir_;
};

inline sensor_msgs::PointCloud2 ToMsg(const RawCloud& c, const std::string& frame = "lidar") {
  sensor_msgs::PointCloud2 m;
  m.header.stamp.fromNSec(uint64_t(c.stamp_ns));
  m.header.frame_id = frame;
  m.height = c.height;
  m.width = c.width;
  m.point_step = c.point_step;
  m.row_step = c.row_step;
  m.is_bigendian = c.is_bigendian;
  m.is_dense = false;
  for (const auto& f : c.fields) {
    sensor_msgs::PointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.datatype;
    pf.count = f.count;
    m.fields.push_back(pf);
  }
  m.data = c.data;
  return m;
}

inline ros::Time RosTime(TimeNs t) {
  ros::Time r;
  r.fromNSec(uint64_t(t));
  return r;
}

inline sensor_msgs::Imu ImuMsg(TimeNs t, double ax, double ay, double az, double gz = 0.0) {
  sensor_msgs::Imu m;
  m.header.stamp = RosTime(t);
  m.linear_acceleration.x = ax;
  m.linear_acceleration.y = ay;
  m.linear_acceleration.z = az;
  m.angular_velocity.z = gz;
  m.orientation_covariance[0] = -1;
  return m;
}

inline std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void WriteAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

// Everything a reader delivers, in order.
struct ReadResult {
  std::vector<ImuSample> imu;
  std::vector<Scan> scans;
  std::vector<char> order;  // 'i' or 's'
  std::vector<TimeNs> last_imu_before_scan;
  SensorReaderStats stats;
  std::string layout;
  Status error;
};

inline ReadResult ReadEverything(const std::string& path, const LidarOptions& lidar,
                                 const ImuOptions& imu_options) {
  ReadResult r;
  auto reader = SensorBagReader::Open(path, lidar, imu_options);
  if (!reader.ok()) {
    r.error = reader.status();
    return r;
  }
  for (int guard = 0; guard < 1000000; ++guard) {
    ImuSample imu;
    Scan scan;
    StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
    if (!m.ok()) {
      r.error = m.status();
      break;
    }
    if (*m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) {
      r.imu.push_back(imu);
      r.order.push_back('i');
    } else {
      r.last_imu_before_scan.push_back(r.imu.empty() ? -1 : r.imu.back().t_ns);
      r.scans.push_back(std::move(scan));
      r.order.push_back('s');
    }
  }
  r.stats = (*reader)->stats();
  r.layout = (*reader)->lidar_layout();
  return r;
}

inline LidarOptions LidarOn(const std::string& topic) {
  LidarOptions o;
  o.topic = topic;
  o.min_range = 0.5;
  o.max_range = 100.0;
  return o;
}
inline ImuOptions ImuOn(const std::string& topic) {
  ImuOptions o;
  o.topic = topic;
  return o;
}

// A synthetic organized Ouster-like sweep: rows x cols, column-wise times
// over 99 ms, every 5th point no-return (zero) and every 13th NaN.
inline Scan SyntheticScan(TimeNs t_start, int rows, int cols, int seed) {
  Scan s;
  s.t_start_ns = t_start;
  s.t_end_ns = t_start + 99 * kMs;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int i = r * cols + c;
      LidarPoint p;
      p.t_ns = t_start + TimeNs(c) * 99 * kMs / (cols - 1);
      p.ring = uint16_t(r);
      p.intensity = float(i % 200);
      if (i % 5 == 0) {
        p.p_lidar.setZero();
      } else if (i % 13 == 0) {
        p.p_lidar = Eigen::Vector3f(std::nanf(""), 1.0f, 1.0f);
      } else {
        const double a = 2.0 * M_PI * c / cols;
        const double range = 3.0 + 0.25 * ((i + seed) % 17);
        p.p_lidar = Eigen::Vector3f(float(range * std::cos(a)), float(range * std::sin(a)),
                                    float(0.2 * r - 0.3));
      }
      s.points.push_back(p);
    }
  }
  return s;
}

inline bool Valid(const LidarPoint& p) { return p.p_lidar.allFinite() && !p.p_lidar.isZero(0.0f); }

}  // namespace rvlio::test
