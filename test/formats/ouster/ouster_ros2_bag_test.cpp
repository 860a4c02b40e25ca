// A ROS 2 Ouster packet bag (MCAP, `ouster_sensor_msgs/msg/PacketMsg` on
// …/lidar_packets and …/imu_packets, the metadata JSON on a
// `std_msgs/msg/String` …/metadata topic, as the ROS 2 driver records them)
// reads as the capture it was made from. The bag is written here from a real
// capture of the Ouster SDK's test data, packet by packet with the capture's
// receive times, by the project's MCAP and CDR writers: no ROS 2 recording of
// packets is among the files other tools wrote.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "ouster_test_util.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/mcap.h"
#include "rvlio/formats/pcap.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

std::string BagCapture(const std::string& name) { return std::string(RVLIO_TEST_DATA) + "/ouster/" + name; }

std::string ReadWholeText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<uint8_t> PacketMessage(const std::vector<uint8_t>& bytes) {
  cdr::Writer w;
  w.Bytes(bytes.data(), bytes.size());
  return w.Take();
}

// The capture's UDP datagrams as a ROS 2 packet bag at `bag_path`: lidar
// packets (the large datagrams) and IMU packets (48 bytes) on their topics,
// the metadata once before them. Returns the number of packets written.
int WritePacketBag(const std::string& pcap_path, const std::string& json_path,
                   const std::string& bag_path) {
  StatusOr<std::unique_ptr<mcap::Writer>> writer = mcap::Writer::Create(bag_path, mcap::WriterOptions());
  EXPECT_TRUE(writer.ok()) << writer.status().message();
  if (!writer.ok()) return 0;
  mcap::Writer& w = **writer;
  const uint16_t packet_schema = *w.AddSchema("ouster_sensor_msgs/msg/PacketMsg", "ros2msg", "uint8[] buf\n");
  const uint16_t string_schema = *w.AddSchema(cdr::kStringType, "ros2msg", "string data\n");
  const uint16_t lidar = *w.AddChannel(packet_schema, "/ouster/lidar_packets", "cdr");
  const uint16_t imu = *w.AddChannel(packet_schema, "/ouster/imu_packets", "cdr");
  const uint16_t meta = *w.AddChannel(string_schema, "/ouster/metadata", "cdr");
  StatusOr<PcapReader> pcap = PcapReader::Open(pcap_path);
  EXPECT_TRUE(pcap.ok()) << pcap.status().message();
  if (!pcap.ok()) return 0;
  UdpDatagram d;
  uint32_t sequence = 0;
  int packets = 0;
  while (*pcap->Next(&d)) {
    mcap::Message m;
    m.log_time_ns = m.publish_time_ns = static_cast<uint64_t>(d.t_ns);
    if (sequence == 0) {  // the driver latches the metadata before the packets
      cdr::Writer text;
      text.String(ReadWholeText(json_path));
      m.channel_id = meta;
      m.sequence = sequence++;
      m.data = text.Take();
      EXPECT_TRUE(w.Write(m).ok());
    }
    if (d.payload.size() != 48 && d.payload.size() < 1000) continue;  // neither kind
    m.channel_id = d.payload.size() == 48 ? imu : lidar;
    m.sequence = sequence++;
    m.data = PacketMessage(d.payload);
    EXPECT_TRUE(w.Write(m).ok());
    ++packets;
  }
  EXPECT_TRUE(w.Close().ok());
  return packets;
}

LidarOptions AllBagReturns(const std::string& metadata = "") {
  LidarOptions lidar;
  lidar.min_range = 0.0;
  lidar.max_range = 1e6;
  lidar.ouster_metadata = metadata;
  return lidar;
}

TEST(OusterRos2Bag, ReadsAsTheCaptureItWasMadeFrom) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_ouster_ros2");
  ASSERT_FALSE(dir.empty());
  const std::string pcap = BagCapture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap");
  const std::string json = BagCapture("OS-1-128_v2.3.0_1024x10.json");
  const std::string bag = dir + "/packets.mcap";
  EXPECT_EQ(WritePacketBag(pcap, json, bag), 192 + 30);  // 3 frames x 64 lidar packets, 30 IMU

  const testing_ouster::Decoded from_pcap = testing_ouster::ReadAll(pcap, AllBagReturns(json), ImuOptions());
  const testing_ouster::Decoded from_bag = testing_ouster::ReadAll(bag, AllBagReturns(), ImuOptions());
  ASSERT_EQ(from_bag.scans.size(), from_pcap.scans.size());
  ASSERT_EQ(from_pcap.scans.size(), 3u);
  for (size_t i = 0; i < from_pcap.scans.size(); ++i) {
    const Scan &a = from_pcap.scans[i], &b = from_bag.scans[i];
    EXPECT_EQ(b.t_start_ns, a.t_start_ns);
    EXPECT_EQ(b.t_end_ns, a.t_end_ns);
    ASSERT_EQ(b.points.size(), a.points.size()) << "scan " << i;
    for (size_t k = 0; k < a.points.size(); ++k) {
      EXPECT_EQ(b.points[k].p_lidar, a.points[k].p_lidar);
      EXPECT_EQ(b.points[k].t_ns, a.points[k].t_ns);
    }
  }
  ASSERT_EQ(from_bag.imu.size(), from_pcap.imu.size());
  ASSERT_EQ(from_pcap.imu.size(), 30u);
  for (size_t i = 0; i < from_pcap.imu.size(); ++i) {
    EXPECT_EQ(from_bag.imu[i].t_ns, from_pcap.imu[i].t_ns);
    EXPECT_EQ(from_bag.imu[i].acc_imu, from_pcap.imu[i].acc_imu);
    EXPECT_EQ(from_bag.imu[i].gyro_imu, from_pcap.imu[i].gyro_imu);
  }

  // `rvlio info` names the ROS 2 storage and the topics it read.
  const testing_cli::ToolRun info = testing_cli::RunTool("info --bag " + bag, dir);
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("/ouster/lidar_packets"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("RNG15_RFL8_NIR8"), std::string::npos) << info.out;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio
