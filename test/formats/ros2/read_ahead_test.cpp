// The ROS 2 reader detects the LiDAR layout at Open by reading ahead on its
// own source (no second reader): the messages read ahead must still reach
// Next, in order, whether the first scan comes early or after more IMU
// messages than the read-ahead holds.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

constexpr int kRows = 4, kCols = 16;
constexpr TimeNs kT0Ns = 1700000000000000000LL;
constexpr TimeNs kImuStepNs = 2500000;  // 400 Hz

Scan SmallSweep(TimeNs t_start_ns) {
  Scan scan;
  scan.t_start_ns = t_start_ns;
  scan.t_end_ns = t_start_ns + 99000000;
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      LidarPoint p;
      p.p_lidar = Eigen::Vector3f(5.0f + r, 0.1f * c, 1.0f);
      p.t_ns = t_start_ns + c * 6000000LL;
      p.ring = static_cast<uint16_t>(r);
      p.intensity = 10.0f;
      scan.points.push_back(p);
    }
  }
  return scan;
}

// `imu_before` IMU samples, then 3 scans 100 ms apart with IMU around them.
void WriteRecording(const std::string& path, const BagWriterOptions& options, int imu_before) {
  auto writer = SensorBagWriter::Create(path, options);
  ASSERT_TRUE(writer.ok()) << writer.status().message();
  const LidarOptions lidar;
  const ImuOptions imu_options;
  const int imu_total = imu_before + 3 * 40 + 40;
  int next_scan = 0;
  for (int i = 0; i < imu_total; ++i) {
    ImuSample imu;
    imu.t_ns = kT0Ns + i * kImuStepNs;
    imu.acc_imu = Eigen::Vector3d(0.01 * (i % 7), 0.0, 9.81);
    imu.gyro_imu = Eigen::Vector3d(0.0, 0.0, 0.001 * (i % 5));
    ASSERT_TRUE((*writer)->WriteImu(imu_options.topic, "imu", imu).ok());
    const TimeNs scan_start = kT0Ns + imu_before * kImuStepNs + next_scan * 100000000LL;
    if (next_scan < 3 && imu.t_ns >= scan_start + 100000000LL) {
      ASSERT_TRUE(
          (*writer)->WriteOusterScan(lidar.topic, "os", SmallSweep(scan_start), kRows, kCols).ok());
      ++next_scan;
    }
  }
  ASSERT_EQ(next_scan, 3);
  ASSERT_TRUE((*writer)->Close().ok());
}

// What a reader delivers: one line per message (kind, time, values).
struct Delivered {
  std::vector<std::string> lines;
  std::string layout_at_open, layout_at_end;
};

Delivered ReadAll(const std::string& path) {
  Delivered out;
  auto reader = SensorBagReader::Open(path, LidarOptions(), ImuOptions());
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  if (!reader.ok()) return out;
  out.layout_at_open = (*reader)->lidar_layout();
  ImuSample imu;
  Scan scan;
  for (;;) {
    StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok() || *m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu)
      out.lines.push_back("imu " + std::to_string(imu.t_ns) + " " +
                          std::to_string(imu.acc_imu.x()) + " " + std::to_string(imu.gyro_imu.z()));
    else
      out.lines.push_back("scan " + std::to_string(scan.t_start_ns) + " " +
                          std::to_string(scan.points.size()));
  }
  out.layout_at_end = (*reader)->lidar_layout();
  return out;
}

class ReadAheadTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    dir_ = testing_cli::MakeTempDir("rvlio_readahead");
    ASSERT_FALSE(dir_.empty());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string dir_;
};

// 50 IMU samples before the first scan (read ahead and replayed), and 60000
// (about 21 MB of IMU messages, more than the read-ahead holds: the layout
// comes from the first scan Next decodes). Every ROS 2 kind delivers what
// the ROS1 bag delivers.
TEST_P(ReadAheadTest, ReadAheadMessagesAreDeliveredInOrder) {
  const int imu_before = GetParam();
  BagWriterOptions ros1;
  WriteRecording(dir_ + "/r.bag", ros1, imu_before);
  const Delivered expected = ReadAll(dir_ + "/r.bag");
  ASSERT_EQ(expected.lines.size(), static_cast<size_t>(imu_before + 3 * 40 + 40 + 3));
  EXPECT_EQ(expected.layout_at_end, "ouster");
  for (const auto& [name, format, compression] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"z.mcap", "mcap", "zstd"}, {"u.mcap", "mcap", "unchunked"}, {"d.db3", "db3", ""}}) {
    SCOPED_TRACE(name);
    BagWriterOptions options;
    options.format = format;
    if (!compression.empty()) options.mcap_compression = compression;
    WriteRecording(dir_ + "/" + name, options, imu_before);
    const Delivered got = ReadAll(dir_ + "/" + name);
    EXPECT_EQ(got.lines, expected.lines);
    EXPECT_EQ(got.layout_at_end, "ouster");
    EXPECT_EQ(got.layout_at_open, imu_before < 1000 ? "ouster" : "");
  }
}

INSTANTIATE_TEST_SUITE_P(FirstScanEarlyAndLate, ReadAheadTest, ::testing::Values(50, 60000));

}  // namespace
}  // namespace rvlio
