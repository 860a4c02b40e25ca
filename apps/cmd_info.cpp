// rvlio info --bag PATH [--lidar-topic T]: what is in a recording and whether its
// LiDAR messages carry per-point times the reader understands.
#include <cstdio>
#include <iostream>
#include <string>

#include "commands.h"
#include "common_options.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::cli {
namespace {

void PrintCloud(const BagTopicInfo& t) {
  if (t.lidar_layout.empty()) return;
  if (!t.decode_error.empty()) {
    std::cout << "    layout: unknown (" << t.decode_error << ")\n";
  } else {
    std::cout << "    layout: " << t.lidar_layout << " (header stamp marks the scan "
              << t.header_stamp << ")\n";
  }
  std::cout << "    fields: " << Join(t.fields, ",") << "\n";
  if (t.decode_error.empty()) {
    std::cout << "    points per scan: " << FormatFixed(t.points_per_scan, 1) << " (mean of first "
              << t.scans_sampled << ")\n";
  }
}

// Seconds with all nine decimals, from the exact ns.
std::string Stamp(TimeNs t_ns) {
  char buf[64];
  const TimeNs s = t_ns / kNsPerSecond, ns = t_ns % kNsPerSecond;
  std::snprintf(buf, sizeof(buf), "%lld.%09lld", static_cast<long long>(s),
                static_cast<long long>(ns < 0 ? -ns : ns));
  return buf;
}

void PrintOuster(const OusterRecordingInfo& o) {
  std::cout << "ouster:\n"
            << "  metadata: " << o.metadata << "\n"
            << "  sensor:   " << o.prod_line << ", firmware " << o.firmware << "\n"
            << "  mode:     " << o.lidar_mode << " (" << o.beams << " beams, " << o.window_columns
            << " of " << o.columns_per_frame << " columns sent)\n"
            << "  profile:  " << o.lidar_profile << (o.lidar_decoded ? "" : " (not decoded)")
            << (o.crc ? " (CRC-64 checked)" : "") << ", IMU " << o.imu_profile << "\n"
            << "  lidar:    " << o.lidar_source << ", " << o.lidar_packets << " packets"
            << (o.lidar_packets == 0 ? " (no lidar packets: IMU samples only)" : "") << "\n"
            << "  frames:   " << o.frames << " (" << FormatFixed(o.frame_rate_hz, 2) << " Hz), "
            << o.incomplete_frames << " incomplete, " << o.missing_columns << " columns missing\n"
            << "  imu:      " << o.imu_source << ", " << o.imu_packets << " packets, "
            << FormatFixed(o.imu_rate_hz, 1) << " Hz\n"
            << "  dropped:  " << o.late_packets << " late packets, " << o.crc_errors
            << " CRC errors, " << o.imu_crc_errors << " IMU CRC errors\n";
}

void Print(const BagInfo& info) {
  std::cout << "bag:      " << info.path << "\n"
            << "storage:  " << info.storage << "\n";
  if (!info.compressions.empty())
    std::cout << "compression: " << Join(info.compressions, ",") << "\n";
  std::cout << "duration: " << FormatFixed(NsToSeconds(info.end_ns - info.start_ns), 3) << " s\n"
            << "start:    " << Stamp(info.start_ns) << " s\n"
            << "end:      " << Stamp(info.end_ns) << " s\n"
            << "messages: " << info.messages << "\n"
            << "topics:\n";
  for (const auto& t : info.topics) {
    std::cout << "  " << t.topic << "  " << t.type << "  " << t.count << " msgs  "
              << FormatFixed(t.rate_hz, 2) << " Hz\n";
    PrintCloud(t);
  }
  if (info.ouster) PrintOuster(*info.ouster);
}

}  // namespace

int CmdInfo(int argc, char** argv) {
  CommandSpec spec{"info",
                   "Lists the topics of a recording (ROS1 bag, ROS 2 .db3 / .mcap / bag folder:\n"
                   "type, count, rate; storage and chunk compression) and, for PointCloud2 and\n"
                   "Livox CustomMsg topics, the detected per-point time layout, the fields and\n"
                   "the mean number of valid points per scan (from the first few messages). For\n"
                   "Ouster packets (.pcap capture, packet bag): sensor, firmware, mode, profile,\n"
                   "frames, IMU rate and dropped packets, from a pass over every packet.",
                   {{"bag", "PATH", "ROS1 bag, .db3, .mcap, ROS 2 bag folder or Ouster .pcap", true, false},
                    {"lidar-topic", "TOPIC", "analyse only this PointCloud2 or CustomMsg topic", false, false},
                    OusterMetadataOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  StatusOr<BagInfo> info = ReadBagInfo(args.Get("bag"), args.Get("lidar-topic"), args.Get("ouster-metadata"));
  if (!info.ok()) return Fail(spec.name, info.status());
  Print(*info);
  for (const std::string& w : info->warnings)
    std::cerr << "rvlio info: warning: " << w << "\n";
  return 0;
}

}  // namespace rvlio::cli
