// The bad-input matrix of `rvlio run` for bag contents, end to end: data
// problems that can be skipped are skipped, counted in summary.json and warned
// about once (exit 0); problems that make the run meaningless stop it with
// exit 2 and one stderr line naming the bag, topic or key. Every case says
// which outputs exist afterwards (none, or complete ones).
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>
#include <rosbag/bag.h>

#include "formats/bag/bag_fixture.h"
#include "badinput_util.h"

namespace rvlio::badinput {
namespace {

namespace fs = std::filesystem;

class BadBagTest : public SimulatedSuite {
 protected:
  // The error case: exit 2, exactly `line` on stderr, no output folder.
  void ExpectStopsBeforeOutput(const ToolRun& r, const std::string& out, const std::string& line) {
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.err, "rvlio run: error: " + line + "\n");
    EXPECT_FALSE(fs::exists(out)) << "nothing was read, so nothing may be written";
  }
  // All four outputs exist and summary.json is complete JSON.
  void ExpectCompleteOutputs(const std::string& out) {
    EXPECT_EQ(Entries(out), OutputNames()) << out;
    EXPECT_FALSE(Summary(out).is_discarded());
  }
};

TEST_F(BadBagTest, TruncatedBagStopsWithOneLineAndWritesNothing) {
  const std::string bytes = ReadFile(Bag());
  for (double fraction : {0.5, 0.999}) {
    const std::string cut = dir_ + "/cut.bag";
    test::WriteAll(cut, bytes.substr(0, static_cast<size_t>(bytes.size() * fraction)));
    const std::string out = dir_ + "/out_cut";
    const ToolRun r = Run(cut, out);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("rvlio run: error: '" + cut + "' is not a readable ROS1 bag (", 0), 0u)
        << r.err;
    EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// rosbag finds messages through the index at the end of the file; a bag cut
// short loses it and is unreadable as a whole (above). A chunk damaged in the
// middle is found only when it is reached: the run keeps what it read before.
TEST_F(BadBagTest, CorruptChunkMidwayWritesWhatWasReadAndExitsTwo) {
  std::string bytes = ReadFile(Bag());
  const std::string chunk_header = std::string("compression=none", 16);
  size_t at = 0;
  for (int k = 0; k < 25; ++k) at = bytes.find(chunk_header, at + 1);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, chunk_header.size(), "compression=zzzz");
  const std::string bad = dir_ + "/corrupt.bag";
  test::WriteAll(bad, bytes);
  const std::string out = dir_ + "/out_corrupt";
  const ToolRun r = Run(bad, out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("rvlio run: error: reading bag '" + bad + "' failed (", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("(outputs hold the scans read before it)\n"), std::string::npos) << r.err;
  ExpectCompleteOutputs(out);
  const int poses = TumPoses(out + "/trajectory.tum");
  EXPECT_GT(poses, 0);
  EXPECT_LT(poses, TumPoses(Clean("trajectory.tum")));
  EXPECT_EQ(Summary(out)["scan_count"].get<int>(), poses);
}

TEST_F(BadBagTest, BagWithoutImuTopicStops) {
  const std::string bag = dir_ + "/no_imu.bag";
  WriteCopy(bag, nullptr, nullptr, kLidarTopic, "");
  const std::string out = dir_ + "/out_no_imu";
  ExpectStopsBeforeOutput(Run(bag, out), out,
                          "imu.topic '/imu/data' is not in bag '" + bag +
                              "'; topics present: /os_cloud_node/points (sensor_msgs/PointCloud2)");
}

TEST_F(BadBagTest, BagWithoutLidarTopicStops) {
  const std::string bag = dir_ + "/no_lidar.bag";
  WriteCopy(bag, nullptr, nullptr, "", kImuTopic);
  const std::string out = dir_ + "/out_no_lidar";
  ExpectStopsBeforeOutput(Run(bag, out), out,
                          "lidar.topic '/os_cloud_node/points' is not in bag '" + bag +
                              "'; topics present: /imu/data (sensor_msgs/Imu)");
}

TEST_F(BadBagTest, WrongTopicNamesStopAndTheListedNamesWork) {
  const std::string bag = dir_ + "/renamed.bag";
  WriteCopy(bag, nullptr, nullptr, "/points", "/imu");
  const std::string present = "; topics present: /imu (sensor_msgs/Imu), /points "
                              "(sensor_msgs/PointCloud2)";
  const std::string out = dir_ + "/out_renamed";
  ExpectStopsBeforeOutput(Run(bag, out), out,
                          "lidar.topic '/os_cloud_node/points' is not in bag '" + bag + "'" + present);
  ExpectStopsBeforeOutput(Run(bag, out, "--set lidar.topic=/points --set imu.topic=/points"), out,
                          "imu.topic '/points' in bag '" + bag +
                              "' has type sensor_msgs/PointCloud2, expected sensor_msgs/Imu" +
                              present);
  // With the names the message lists, the same data gives the clean result.
  const ToolRun ok = Run(bag, out, "--set lidar.topic=/points --set imu.topic=/imu");
  ASSERT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_EQ(ok.err, "");
  EXPECT_EQ(ReadFile(out + "/trajectory.tum"), ReadFile(Clean("trajectory.tum")));
}

TEST_F(BadBagTest, PointCloudWithoutTimeFieldStops) {
  const std::string bag = dir_ + "/no_time.bag";
  {
    rosbag::Bag b;
    b.open(bag, rosbag::bagmode::Write);
    test::RawCloud c = test::MakeCloud({{"x", 0, kPointFloat32, 1}, {"y", 4, kPointFloat32, 1},
                                        {"z", 8, kPointFloat32, 1},
                                        {"intensity", 12, kPointFloat32, 1}},
                                       16, "", "");
    for (const Message& m : *messages_) {
      if (m.is_imu) {
        b.write(kImuTopic, test::RosTime(m.imu.t_ns),
                test::ImuMsg(m.imu.t_ns, m.imu.acc_imu.x(), m.imu.acc_imu.y(), m.imu.acc_imu.z()));
        continue;
      }
      c.stamp_ns = m.scan.t_start_ns;
      c.Resize(static_cast<uint32_t>(m.scan.points.size()));
      for (uint32_t i = 0; i < c.width; ++i) {
        const auto& p = m.scan.points[i].p_lidar;
        c.SetPoint(i, p.x(), p.y(), p.z(), 1.0, 0.0, 0);
      }
      b.write(kLidarTopic, test::RosTime(m.scan.t_end_ns), test::ToMsg(c));
    }
    b.close();
  }
  const std::string out = dir_ + "/out_no_time";
  const ToolRun r = Run(bag, out, "--set lidar.type=auto");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("PointCloud2 on /os_cloud_node/points has no per-point time field; fields "
                       "are x,y,z,intensity"),
            std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

// NaN, Inf and zero (no-return) points are routine in organized clouds: they
// are dropped and counted, with no warning, and change nothing else.
TEST_F(BadBagTest, NanInfAndZeroPointsAreDroppedAndCountedSilently) {
  int64_t bad = 0;
  const float inf = std::numeric_limits<float>::infinity();
  const std::string bag = dir_ + "/nan_points.bag";
  WriteCopy(bag, [&](int, Scan* scan) {
    for (size_t i = 0; i < scan->points.size(); ++i) {
      Eigen::Vector3f& p = scan->points[i].p_lidar;
      if (i % 7 == 0) p.x() = std::nanf("");
      else if (i % 11 == 0) p.z() = -inf;
      else if (i % 13 == 0) p.setZero();
      else continue;
      ++bad;
    }
  });
  const std::string out = dir_ + "/out_nan_points";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  ExpectCompleteOutputs(out);
  const auto s = Summary(out);
  EXPECT_EQ(s["stats"]["reader"]["invalid_points"].get<int64_t>(), bad);
  EXPECT_EQ(s["stats"]["reader"]["empty_scans"].get<int>(), 0);
  EXPECT_EQ(s["scan_count"], Summary(dir_ + "/clean")["scan_count"]);
  EXPECT_TRUE(s["warnings"].empty()) << s["warnings"];
}

// No scan survives: one line with the counts, and nothing written (no output
// folder; an existing one keeps its earlier outputs as they were).
TEST_F(BadBagTest, AllPointsOutOfRangeStopsNamingTheRangeKeysAndWritesNothing) {
  const std::string range = "--set lidar.min_range=0.5 --set lidar.max_range=0.6";
  const std::string out = dir_ + "/out_range";
  const ToolRun r = Run(Bag(), out, range);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  const auto clean = Summary(dir_ + "/clean");
  const int64_t scans = clean["stats"]["reader"]["scans"].get<int64_t>();
  const int64_t invalid = clean["stats"]["reader"]["invalid_points"].get<int64_t>();
  const std::string head = "rvlio run: error: every one of the " + std::to_string(scans) +
                           " scans on lidar.topic '/os_cloud_node/points' in " + Bag() +
                           " is empty after dropping " + std::to_string(invalid) + " invalid and ";
  const std::string tail = " out-of-range points (lidar.min_range 0.5 m, lidar.max_range 0.6 m)\n";
  ASSERT_EQ(r.err.rfind(head, 0), 0u) << r.err;
  ASSERT_GT(r.err.size(), head.size() + tail.size()) << r.err;
  EXPECT_EQ(r.err.substr(r.err.size() - tail.size()), tail) << r.err;
  const std::string count = r.err.substr(head.size(), r.err.size() - head.size() - tail.size());
  EXPECT_GT(std::stoll(count), 100000) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "no scan was done, so nothing may be written";

  const std::string earlier = dir_ + "/out_range_earlier";
  fs::create_directories(earlier);
  for (const std::string& name : OutputNames()) fs::copy_file(Clean(name), earlier + "/" + name);
  const ToolRun again = Run(Bag(), earlier, range);
  EXPECT_EQ(again.exit_code, 2) << again.err;
  EXPECT_EQ(Entries(earlier), OutputNames());
  for (const std::string& name : OutputNames())
    EXPECT_EQ(ReadFile(earlier + "/" + name), ReadFile(Clean(name))) << name;
}

TEST_F(BadBagTest, EmptyScansAreSkippedCountedAndWarnedOnce) {
  int emptied = 0;
  const std::string bag = dir_ + "/empty_scans.bag";
  WriteCopy(bag, [&](int index, Scan* scan) {
    if (index < 15 || index % 4 != 0) return;
    for (auto& p : scan->points) p.p_lidar.setZero();
    ++emptied;
  });
  ASSERT_EQ(emptied, 6);
  const std::string out = dir_ + "/out_empty_scans";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "rvlio run: warning: 6 scans on lidar.topic '/os_cloud_node/points' had no "
                   "valid point in range and were skipped\n");
  ExpectCompleteOutputs(out);
  const auto s = Summary(out);
  EXPECT_EQ(s["stats"]["reader"]["empty_scans"], 6);
  EXPECT_EQ(s["scan_count"].get<int>(), Summary(dir_ + "/clean")["scan_count"].get<int>() - 6);
  EXPECT_EQ(s["warnings"].size(), 1u);
}

// Duplicated, older and NaN IMU samples are recorded between the good ones
// (record time just after a good sample): all are dropped and counted, and
// what remains is exactly the clean stream, so the trajectory is the clean one.
TEST_F(BadBagTest, DuplicateOlderAndNanImuSamplesAreDroppedCountedAndWarned) {
  const std::string bag = dir_ + "/imu_stamps.bag";
  WriteCopy(bag);
  int duplicates = 0, older = 0, nan = 0, index = 0;
  {
    rosbag::Bag b;
    b.open(bag, rosbag::bagmode::Append);
    for (const Message& m : *messages_) {
      if (!m.is_imu || ++index % 10 != 0) continue;
      const ImuSample& s = m.imu;
      const auto msg = [](TimeNs t, const ImuSample& v) {
        return test::ImuMsg(t, v.acc_imu.x(), v.acc_imu.y(), v.acc_imu.z(), v.gyro_imu.z());
      };
      b.write(kImuTopic, test::RosTime(s.t_ns + 1), msg(s.t_ns, s));  // duplicate
      ++duplicates;
      if (index % 20 == 0) {
        b.write(kImuTopic, test::RosTime(s.t_ns + 2), msg(s.t_ns - 2 * test::kMs, s));  // older
        ++older;
      }
      if (index % 30 == 0) {
        ImuSample bad = s;
        bad.acc_imu.y() = std::nan("");
        b.write(kImuTopic, test::RosTime(s.t_ns + 3), msg(s.t_ns + test::kMs, bad));
        ++nan;
      }
    }
    b.close();
  }
  ASSERT_GT(nan, 10);
  const std::string out = dir_ + "/out_imu_stamps";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string w = "rvlio run: warning: ";
  EXPECT_EQ(r.err,
            w + std::to_string(nan) + " IMU samples on imu.topic '/imu/data' with NaN/Inf values "
                "were dropped\n" +
            w + std::to_string(duplicates) + " IMU samples on imu.topic '/imu/data' repeat the "
                "previous stamp and were dropped\n" +
            w + std::to_string(older) + " IMU samples on imu.topic '/imu/data' are older than "
                "the previous one and were dropped\n");
  const auto s = Summary(out);
  EXPECT_EQ(s["stats"]["reader"]["imu_duplicates"], duplicates);
  EXPECT_EQ(s["stats"]["reader"]["imu_non_monotonic"], older);
  EXPECT_EQ(s["stats"]["reader"]["imu_invalid"], nan);
  EXPECT_EQ(ReadFile(out + "/trajectory.tum"), ReadFile(Clean("trajectory.tum")));
}

TEST_F(BadBagTest, ImuGapIsBridgedCountedAndWarned) {
  const TimeNs t0 = messages_->front().imu.t_ns;
  const TimeNs gap_from = t0 + 2500 * test::kMs, gap_to = t0 + 2800 * test::kMs;
  const std::string bag = dir_ + "/imu_gap.bag";
  WriteCopy(bag, nullptr,
            [&](const ImuSample& s) { return s.t_ns <= gap_from || s.t_ns >= gap_to; });
  const std::string out = dir_ + "/out_imu_gap";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "rvlio run: warning: IMU gaps longer than imu.max_gap 0.1 s on imu.topic "
                   "'/imu/data': 1 (longest 0.300 s) were bridged by the estimator\n");
  ExpectCompleteOutputs(out);
  const auto s = Summary(out);
  EXPECT_EQ(s["stats"]["reader"]["imu_gaps"], 1);
  EXPECT_EQ(s["stats"]["imu_gaps_over_scan"], 1);  // the estimator's count, same imu.max_gap
  EXPECT_NEAR(s["stats"]["reader"]["imu_max_gap_s"].get<double>(), 0.3, 1e-9);
  EXPECT_EQ(s["scan_count"], Summary(dir_ + "/clean")["scan_count"]);
  // 0.3 s of motion predicted from nothing but the scans: still on track.
  const auto e = testing_cli::EvalJson(dir_ + "/data/tunnel_gt.tum", out + "/trajectory.tum", dir_);
  ASSERT_FALSE(e.is_null());
  EXPECT_LT(e["ape"]["rmse"].get<double>(), 0.05);
}

TEST_F(BadBagTest, LidarStartingBeforeTheImuSkipsThoseScans) {
  const TimeNs imu_from = messages_->front().imu.t_ns + 450 * test::kMs;
  int early = 0;
  bool imu_seen = false;
  for (const Message& m : *messages_) {
    if (m.is_imu) imu_seen = imu_seen || m.imu.t_ns >= imu_from;
    else if (!imu_seen) ++early;
  }
  ASSERT_GE(early, 4);
  const std::string bag = dir_ + "/late_imu.bag";
  WriteCopy(bag, nullptr, [&](const ImuSample& s) { return s.t_ns >= imu_from; });
  const std::string out = dir_ + "/out_late_imu";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "rvlio run: warning: " + std::to_string(early) +
                       " scans on lidar.topic '/os_cloud_node/points' came before the first IMU "
                       "sample and were skipped\n");
  ExpectCompleteOutputs(out);
  const auto s = Summary(out);
  EXPECT_EQ(s["stats"]["reader"]["scans_before_first_imu"], early);
  EXPECT_GE(s["stats"]["scans_before_imu"].get<int>(), early);
  EXPECT_GT(s["scan_count"].get<int>(), 20);
}

}  // namespace
}  // namespace rvlio::badinput
