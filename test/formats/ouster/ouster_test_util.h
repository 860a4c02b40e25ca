#pragma once
// The test/formats/ouster helpers: a whole recording read through SensorBagReader.
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "rvlio/formats/sensor_bag.h"

namespace rvlio::testing_ouster {

struct Decoded {
  std::vector<Scan> scans;
  std::vector<ImuSample> imu;
  SensorReaderStats stats;
  std::vector<std::string> warnings;
};

// Every message of `path` (a failure is a test failure).
inline Decoded ReadAll(const std::string& path, const LidarOptions& lidar, const ImuOptions& imu) {
  Decoded out;
  StatusOr<std::unique_ptr<SensorBagReader>> reader = SensorBagReader::Open(path, lidar, imu);
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  if (!reader.ok()) return out;
  ImuSample s;
  Scan scan;
  while (true) {
    StatusOr<SensorMessage> m = (*reader)->Next(&s, &scan);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok() || *m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) out.imu.push_back(s);
    else out.scans.push_back(scan);
  }
  out.stats = (*reader)->stats();
  out.warnings = (*reader)->warnings();
  return out;
}

}  // namespace rvlio::testing_ouster
