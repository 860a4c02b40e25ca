// `rvlio simulate --format ouster-pcap`: the capture (lidar and IMU packets,
// IPv4-fragmented, with its metadata JSON) decodes bit for bit to what the
// bag of the same simulation holds. The bag carries the packets'
// quantization (ranges in mm from the beam origin, reflectivity as uint8,
// accelerations in g and rates in deg/s as float32), so "exact" is exact:
// every point coordinate, time, ring and intensity and every IMU value.
#include <algorithm>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "ouster_test_util.h"
#include "rvlio/api.h"
#include "rvlio/config/config.h"
#include "rvlio/formats/pcap.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

using Stream = testing_ouster::Decoded;

Stream ReadAll(const std::string& path, const Configuration& o) {
  return testing_ouster::ReadAll(path, o.lidar, o.imu);
}

void SortPoints(Scan* scan) {
  std::sort(scan->points.begin(), scan->points.end(), [](const LidarPoint& a, const LidarPoint& b) {
    return std::tie(a.t_ns, a.ring) < std::tie(b.t_ns, b.ring);
  });
}

TEST(OusterSimTest, CaptureDecodesExactlyToTheBagOfTheSameSimulation) {
  const fs::path dir = fs::temp_directory_path() / ("rvlio_ouster_sim_" + std::to_string(::getpid()));
  SimulateArgs args;
  args.preset = "tunnel";
  args.duration_s = 1.5;
  args.out_dir = dir.string();
  args.name = "sim";
  args.format = "ouster-pcap";
  StatusOr<SimulateResult> sim = SimulateRecording(args);
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  EXPECT_EQ(sim->bag_path, (dir / "sim.pcap").string());
  ASSERT_TRUE(fs::exists(dir / "sim.json"));
  ASSERT_TRUE(fs::exists(dir / "sim.bag"));
  std::vector<std::string> warnings;
  StatusOr<Configuration> options = LoadConfig({(dir / "sim.yaml").string()}, {}, &warnings);
  ASSERT_TRUE(options.ok()) << options.status().message();

  const Stream pcap = ReadAll((dir / "sim.pcap").string(), *options);
  const Stream bag = ReadAll((dir / "sim.bag").string(), *options);
  ASSERT_EQ(pcap.scans.size(), static_cast<size_t>(sim->scans));
  ASSERT_EQ(pcap.scans.size(), bag.scans.size());
  ASSERT_EQ(pcap.imu.size(), static_cast<size_t>(sim->imu_samples));
  ASSERT_EQ(pcap.imu.size(), bag.imu.size());
  for (size_t i = 0; i < pcap.imu.size(); ++i) {
    EXPECT_EQ(pcap.imu[i].t_ns, bag.imu[i].t_ns);
    EXPECT_EQ(pcap.imu[i].acc_imu, bag.imu[i].acc_imu) << i;
    EXPECT_EQ(pcap.imu[i].gyro_imu, bag.imu[i].gyro_imu) << i;
  }
  size_t points = 0;
  for (size_t k = 0; k < pcap.scans.size(); ++k) {
    Scan a = pcap.scans[k], b = bag.scans[k];
    EXPECT_EQ(a.t_start_ns, b.t_start_ns);
    EXPECT_EQ(a.t_end_ns, b.t_end_ns);
    ASSERT_EQ(a.points.size(), b.points.size()) << "scan " << k;
    SortPoints(&a);
    SortPoints(&b);
    for (size_t i = 0; i < a.points.size(); ++i) {
      ASSERT_EQ(a.points[i].p_lidar, b.points[i].p_lidar) << "scan " << k << " point " << i;
      ASSERT_EQ(a.points[i].t_ns, b.points[i].t_ns);
      ASSERT_EQ(a.points[i].ring, b.points[i].ring);
      ASSERT_EQ(a.points[i].intensity, b.points[i].intensity);
    }
    points += a.points.size();
  }
  EXPECT_GT(points, 10000u);
  EXPECT_EQ(pcap.stats.out_of_range_points, bag.stats.out_of_range_points);

  // The large lidar packets went through IPv4 fragmentation.
  StatusOr<PcapReader> reader = PcapReader::Open((dir / "sim.pcap").string());
  ASSERT_TRUE(reader.ok());
  UdpDatagram d;
  while (true) {
    StatusOr<bool> got = reader->Next(&d);
    ASSERT_TRUE(got.ok());
    if (!*got) break;
  }
  EXPECT_GT(reader->stats().fragments, 0);
  EXPECT_EQ(reader->stats().incomplete_datagrams, 0);

  // --format ouster-bag: the same packets in a ROS1 bag as the driver
  // records them (metadata on its topic), read by the packet-bag reader
  // with the configuration written beside it: the capture's scans and IMU
  // samples.
  args.out_dir = (dir / "packets").string();
  args.format = "ouster-bag";
  StatusOr<SimulateResult> packets = SimulateRecording(args);
  ASSERT_TRUE(packets.ok()) << packets.status().message();
  EXPECT_EQ(packets->bag_path, (dir / "packets" / "sim.bag").string());
  EXPECT_EQ(packets->bag_path, SimulatedRecordingPath(args));
  ASSERT_TRUE(fs::exists(dir / "packets" / "sim.json"));
  StatusOr<Configuration> packet_options =
      LoadConfig({(dir / "packets" / "sim.yaml").string()}, {}, &warnings);
  ASSERT_TRUE(packet_options.ok()) << packet_options.status().message();
  EXPECT_EQ(packet_options->lidar.topic, "/ouster/lidar_packets");
  EXPECT_EQ(packet_options->imu.topic, "/ouster/imu_packets");
  const Stream from_bag = ReadAll(packets->bag_path, *packet_options);
  ASSERT_EQ(from_bag.scans.size(), pcap.scans.size());
  for (size_t k = 0; k < pcap.scans.size(); ++k) {
    ASSERT_EQ(from_bag.scans[k].points.size(), pcap.scans[k].points.size()) << "scan " << k;
    EXPECT_EQ(from_bag.scans[k].t_end_ns, pcap.scans[k].t_end_ns);
    for (size_t i = 0; i < pcap.scans[k].points.size(); ++i)
      ASSERT_EQ(from_bag.scans[k].points[i].p_lidar, pcap.scans[k].points[i].p_lidar) << k << " " << i;
  }
  ASSERT_EQ(from_bag.imu.size(), pcap.imu.size());
  for (size_t i = 0; i < pcap.imu.size(); ++i) {
    EXPECT_EQ(from_bag.imu[i].t_ns, pcap.imu[i].t_ns);
    EXPECT_EQ(from_bag.imu[i].acc_imu, pcap.imu[i].acc_imu) << i;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace rvlio
