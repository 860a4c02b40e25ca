// SensorBagReader::Open with a ReceiveTimeRange: exactly the messages a full
// read delivers whose receive time lies in the range, for every storage the
// writer produces (ROS1, MCAP chunked zstd / uncompressed / unchunked, db3, a
// ROS 2 folder split into two MCAP files), with range edges on exact receive
// stamps and empty ranges.
#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bag_fixture.h"

namespace rvlio::test {
namespace {

const std::string kRangeCloudTopic = "/os_cloud_node/points";
const std::string kRangeImuTopic = "/imu/data";
constexpr int kScans = 30;
constexpr TimeNs kScanEndNs = 99 * kMs;  // SyntheticScan: receive time = start + 99 ms

struct StorageCase {
  const char* name;
  const char* format;
  const char* compression;
};

class ReceiveRangeTest : public TempDirTest, public ::testing::WithParamInterface<StorageCase> {
 protected:
  // kScans sweeps of 16 x 128 (100 ms apart) and 200 Hz IMU over their span;
  // the "folder" case: a ROS 2 bag folder split into two MCAP files at scan 12.
  std::string WriteRecording() {
    const std::string name = GetParam().name;
    if (name != "folder") {
      const std::string path = Path("rec." + name);
      WritePart(path, GetParam().format, 0, kScans);
      return path;
    }
    const std::string folder = Path("split");
    std::filesystem::create_directory(folder);
    WritePart(folder + "/split_0.mcap", "mcap", 0, 12);
    WritePart(folder + "/split_1.mcap", "mcap", 12, kScans);
    WriteAll(folder + "/metadata.yaml",
             "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n"
             "  relative_file_paths:\n    - split_0.mcap\n    - split_1.mcap\n");
    return folder;
  }

  // Scans first_scan..end_scan-1 and the IMU samples up to their ends (from
  // the previous scan's end on).
  void WritePart(const std::string& path, const std::string& format, int first_scan,
                 int end_scan) {
    BagWriterOptions options;
    options.format = format;
    options.mcap_compression = GetParam().compression;
    auto writer = SensorBagWriter::Create(path, options);
    EXPECT_TRUE(writer.ok());
    int imu_index = first_scan == 0 ? 0 : (first_scan * 100 - 1) / 5 + 1;
    for (int k = first_scan; k < end_scan; ++k) {
      const Scan scan = SyntheticScan(kT0 + k * 100 * kMs, 16, 128, k);
      for (; kT0 + imu_index * 5 * kMs <= scan.t_end_ns; ++imu_index) {
        ImuSample s;
        s.t_ns = kT0 + imu_index * 5 * kMs;
        s.acc_imu = Eigen::Vector3d(0.5, -0.25, 9.75);
        s.gyro_imu = Eigen::Vector3d(0.125, 0.0, -0.5 + 0.001 * imu_index);
        EXPECT_TRUE((*writer)->WriteImu(kRangeImuTopic, "imu_link", s).ok());
      }
      EXPECT_TRUE((*writer)->WriteOusterScan(kRangeCloudTopic, "os_lidar", scan, 16, 128).ok());
    }
    EXPECT_TRUE((*writer)->Close().ok());
  }
};

// A delivered message: its kind and receive time (the writer's stamps).
struct Delivered {
  char kind;
  TimeNs receive_ns;
  size_t points;
  bool operator==(const Delivered& o) const {
    return kind == o.kind && receive_ns == o.receive_ns && points == o.points;
  }
};

std::vector<Delivered> ReadDelivered(const std::string& path,
                                     const std::optional<ReceiveTimeRange>& range) {
  std::vector<Delivered> out;
  auto reader = SensorBagReader::Open(path, LidarOn(kRangeCloudTopic), ImuOn(kRangeImuTopic), range);
  EXPECT_TRUE(reader.ok()) << reader.status().message();
  if (!reader.ok()) return out;
  ImuSample imu;
  Scan scan;
  for (;;) {
    StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok() || *m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) out.push_back({'i', imu.t_ns, 0});
    else out.push_back({'s', scan.t_start_ns + kScanEndNs, scan.points.size()});
  }
  EXPECT_EQ((*reader)->stats().scans + (*reader)->stats().imu_samples,
            static_cast<int64_t>(out.size()));
  return out;
}

TEST_P(ReceiveRangeTest, DeliversExactlyTheMessagesOfTheRange) {
  const std::string path = WriteRecording();
  const std::vector<Delivered> all = ReadDelivered(path, std::nullopt);
  ASSERT_EQ(std::count_if(all.begin(), all.end(), [](const Delivered& d) { return d.kind == 's'; }),
            kScans);
  const TimeNs scan_10 = kT0 + 10 * 100 * kMs + kScanEndNs;  // a scan's receive time
  const TimeNs imu_300 = kT0 + 300 * 5 * kMs;                // an IMU sample's
  const std::vector<ReceiveTimeRange> ranges = {
      {scan_10, imu_300},
      {scan_10, scan_10},
      {imu_300, imu_300},
      {scan_10 + 1, scan_10 + 2 * kMs},  // between two messages: none
      {imu_300, scan_10},                // first > last: none
      {0, kT0 - 1},                      // before the recording: none
      {kT0 + 10 * 1000 * kMs, kT0 + 20 * 1000 * kMs},  // after it: none
      {-5, kT0 + 1000 * 1000 * kMs},                    // all of it
      {kT0, kT0 + 29 * 100 * kMs + kScanEndNs}};        // exactly its first and last
  for (const ReceiveTimeRange& range : ranges) {
    SCOPED_TRACE("[" + std::to_string(range.first_ns - kT0) + ", " +
                 std::to_string(range.last_ns - kT0) + "] ns after the first message");
    std::vector<Delivered> want;
    for (const Delivered& d : all)
      if (d.receive_ns >= range.first_ns && d.receive_ns <= range.last_ns) want.push_back(d);
    EXPECT_EQ(ReadDelivered(path, range), want);
  }
}

INSTANTIATE_TEST_SUITE_P(Storages, ReceiveRangeTest,
                         ::testing::Values(StorageCase{"bag", "ros1", "zstd"},
                                           StorageCase{"mcap", "mcap", "zstd"},
                                           StorageCase{"mcap_none", "mcap", "none"},
                                           StorageCase{"mcap_unchunked", "mcap", "unchunked"},
                                           StorageCase{"db3", "db3", "zstd"},
                                           StorageCase{"folder", "mcap", "zstd"}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace rvlio::test
