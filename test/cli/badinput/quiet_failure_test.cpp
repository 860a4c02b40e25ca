// The bad-input matrix, continued: inputs on which a run used to go wrong
// quietly (exit 0 and no word, a misleading message, or a file written
// outside --out). Each case states what happens now.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <tuple>

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "formats/bag/bag_fixture.h"
#include "badinput_util.h"

namespace rvlio::badinput {
namespace {

namespace fs = std::filesystem;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The stamps of a TUM file, in file order.
std::vector<double> TumStamps(const std::string& path) {
  std::vector<double> stamps;
  std::istringstream in(ReadFile(path));
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') stamps.push_back(std::stod(line));
  return stamps;
}

class QuietFailureTest : public SimulatedSuite {
 protected:
  // Copies the ROS1 bag `from` to `to` record by record (same record times),
  // letting `edit` change the header stamp of LiDAR message `index`.
  static void CopyEditingCloudStamp(const std::string& from, const std::string& to,
                                    const std::function<void(int, ros::Time*)>& edit) {
    rosbag::Bag in, out;
    in.open(from, rosbag::bagmode::Read);
    out.open(to, rosbag::bagmode::Write);
    rosbag::View view(in);
    int index = 0;
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() != kLidarTopic) {
        out.write(m.getTopic(), m.getTime(), m);
        continue;
      }
      auto cloud = m.instantiate<sensor_msgs::PointCloud2>();
      ASSERT_TRUE(cloud != nullptr);
      edit(index++, &cloud->header.stamp);
      out.write(m.getTopic(), m.getTime(), *cloud);
    }
    out.close();
  }

  // A copy whose scans have their point times (relative to the scan start)
  // multiplied by `factor`: 0 (all zero), 1e-6 (milliseconds written where
  // nanoseconds belong), 1e-3 (microseconds).
  static std::string WithPointTimesScaled(const std::string& name, double factor) {
    const std::string bag = dir_ + "/" + name + ".bag";
    WriteCopy(bag, [factor](int, Scan* scan) {
      for (LidarPoint& p : scan->points)
        p.t_ns = scan->t_start_ns + static_cast<TimeNs>(factor * (p.t_ns - scan->t_start_ns));
    });
    return bag;
  }
};

// Item: a .db3 on read-only storage, read by a user who cannot write its
// folder, opens; reading never creates -shm/-wal files next to it.
TEST_F(QuietFailureTest, Db3OnReadOnlyStorageOpensForAnotherUserAndLeavesNoSideFiles) {
  const std::string folder = dir_ + "/ro_db3";
  fs::create_directories(folder);
  const std::string db3 = folder + "/talker.db3";
  WriteCopy(db3);
  {  // rosbag2 writes WAL-mode databases: header bytes 18 and 19 = 2
    std::fstream f(db3, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(18);
    f.write("\x02\x02", 2);
  }
  const ToolRun writable = RunToolWith("info --bag " + db3, dir_);
  EXPECT_EQ(writable.exit_code, 0) << writable.err;
  EXPECT_EQ(Entries(folder), std::vector<std::string>{"talker.db3"});

  std::string as_other_user;
  if (::geteuid() == 0) {
    const std::string drop = "setpriv --reuid=nobody --regid=nogroup --clear-groups";
    if (std::system((drop + " true >/dev/null 2>&1").c_str()) != 0)
      GTEST_SKIP() << "cannot drop privileges with setpriv";
    as_other_user = drop;
  }
  ASSERT_EQ(::chmod(db3.c_str(), 0444), 0);
  ASSERT_EQ(::chmod(folder.c_str(), 0555), 0);
  ASSERT_EQ(::chmod(dir_.c_str(), 0755), 0);  // the suite folder: traversable by nobody
  const ToolRun ro = RunToolWith("info --bag " + db3, dir_, "", as_other_user);
  EXPECT_EQ(ro.exit_code, 0) << ro.err;
  EXPECT_TRUE(Contains(ro.out, kLidarTopic)) << ro.out;
  EXPECT_EQ(ro.err, "");
  EXPECT_EQ(Entries(folder), std::vector<std::string>{"talker.db3"});
  ::chmod(folder.c_str(), 0755);
}

// Item: `--out ""` is refused by every command that writes a folder.
TEST_F(QuietFailureTest, EmptyOutputFolderIsRefused) {
  const std::string bag = Bag(), init = Clean("trajectory.tum");
  for (const std::string& args :
       {"run --bag " + bag + " --config " + Sensors() + " --out ''",
        "run --bag " + bag + " --config " + Sensors() + " --out=",
        "refine --bag " + bag + " --config " + Sensors() + " --init " + init + " --out ''",
        "merge --chunks " + dir_ + "/clean --out ''"}) {
    const ToolRun r = RunToolWith(args, dir_);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_TRUE(Contains(r.err, "option --out has an empty value")) << r.err;
  }
}

// Item: a scan whose header stamp jumps 0.5 s ahead (a bit flip; record
// order unchanged) is the one skipped (scans_stamp_ahead), not the five
// good scans after it, which it overtook; the trajectory evaluates as the
// clean one does. (This case used to expect those five scans skipped as out
// of order.)
TEST_F(QuietFailureTest, ScanStampJumpingAheadCostsOnlyItsScan) {
  const std::string plain = dir_ + "/jump_plain.bag", bag = dir_ + "/jump.bag";
  WriteCopy(plain);
  CopyEditingCloudStamp(plain, bag, [](int index, ros::Time* stamp) {
    if (index == 25) *stamp = test::RosTime(static_cast<TimeNs>(stamp->toNSec()) + 500 * test::kMs);
  });
  const std::string out = dir_ + "/out_jump";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<double> t = TumStamps(out + "/trajectory.tum");
  for (size_t i = 1; i < t.size(); ++i) EXPECT_LT(t[i - 1], t[i]) << "pose " << i;
  const auto s = Summary(out), clean = Summary(dir_ + "/clean");
  EXPECT_EQ(s["stats"]["scans_out_of_order"], 0);
  EXPECT_EQ(s["stats"]["scans_stamp_ahead"], 1);
  EXPECT_EQ(s["scan_count"].get<int>(), clean["scan_count"].get<int>() - 1);
  EXPECT_TRUE(Contains(r.err, "1 scans were skipped: their stamps jumped ahead")) << r.err;
  const auto ate = [this](const std::string& folder) {
    const auto j = testing_cli::EvalJson(dir_ + "/data/tunnel_gt.tum", folder + "/trajectory.tum", dir_);
    return j.is_null() ? 1e9 : j["ape"]["rmse"].get<double>();
  };
  EXPECT_LT(ate(out), 1.2 * ate(dir_ + "/clean"));
}

// Item: a scan repeating the previous scan's stamp is counted as out of
// order, not as a scan before the IMU: in the middle of the recording and
// where the scan it repeats came during the IMU initialization (the first
// scan queued; there the repeated stamp was counted in scans_before_imu,
// which the middle case alone did not show).
TEST_F(QuietFailureTest, RepeatedScanStampIsCountedOutOfOrder) {
  const auto clean = Summary(dir_ + "/clean");
  const int first_queued = clean["stats"]["scans_before_imu"].get<int>();
  for (int repeated : {first_queued, 25}) {
    SCOPED_TRACE(repeated);
    const std::string name = "repeat" + std::to_string(repeated);
    const std::string plain = dir_ + "/" + name + "_plain.bag", bag = dir_ + "/" + name + ".bag";
    WriteCopy(plain);
    ros::Time previous;
    CopyEditingCloudStamp(plain, bag, [&previous, repeated](int index, ros::Time* stamp) {
      if (index == repeated) *stamp = previous;
      previous = *stamp;
    });
    const std::string out = dir_ + "/out_" + name;
    const ToolRun r = Run(bag, out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto s = Summary(out);
    EXPECT_EQ(s["stats"]["scans_out_of_order"], 1);
    EXPECT_EQ(s["stats"]["scans_before_imu"], clean["stats"]["scans_before_imu"]);
    EXPECT_EQ(s["scan_count"].get<int>(), clean["scan_count"].get<int>() - 1);
    EXPECT_TRUE(Contains(r.err, "1 scans were skipped: their stamps repeat")) << r.err;
  }
}

// Item: a scan stamped 0.5 s ahead near the end of a --duration window no
// longer ends the read there (the window ended at the first message past
// it): the window keeps the scans after it, all the clean run has in it but
// the edited one.
TEST_F(QuietFailureTest, StampAheadNearTheWindowEndKeepsTheWindow) {
  const std::string plain = dir_ + "/win_plain.bag", bag = dir_ + "/win_jump.bag";
  WriteCopy(plain);
  CopyEditingCloudStamp(plain, bag, [](int index, ros::Time* stamp) {
    if (index == 30) *stamp = test::RosTime(static_cast<TimeNs>(stamp->toNSec()) + 500 * test::kMs);
  });
  constexpr double kDurationS = 3.25;  // from the first message; scan 30 ends at about 3.1 s
  const ToolRun r = Run(bag, dir_ + "/out_win_jump", "--duration " + std::to_string(kDurationS));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double first_s = NsToSeconds(messages_->front().is_imu ? messages_->front().imu.t_ns
                                                                : messages_->front().scan.t_end_ns);
  int clean_in_window = 0;
  for (double t : TumStamps(Clean("trajectory.tum"))) clean_in_window += t - first_s <= kDurationS;
  const auto s = Summary(dir_ + "/out_win_jump");
  EXPECT_EQ(s["scan_count"].get<int>(), clean_in_window - 1);
  EXPECT_EQ(s["stats"]["scans_out_of_order"], 0);
}

// Item: an IMU that stops before the LiDAR: the scans past its end (by more
// than imu.max_gap) are not estimated, and the run says so.
TEST_F(QuietFailureTest, ImuStoppingBeforeTheLidarSkipsAndReportsTheScansPastIt) {
  const TimeNs imu_end = messages_->front().imu.t_ns + 3000 * test::kMs;
  const std::string bag = dir_ + "/imu_stops.bag";
  WriteCopy(bag, nullptr, [imu_end](const ImuSample& s) { return s.t_ns <= imu_end; });
  const std::string out = dir_ + "/out_imu_stops";
  const ToolRun r = Run(bag, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto s = Summary(out);
  EXPECT_GE(s["stats"]["scans_after_imu"].get<int>(), 8);
  EXPECT_TRUE(Contains(r.err, "after the last IMU sample")) << r.err;
  const std::vector<double> t = TumStamps(out + "/trajectory.tum");
  ASSERT_FALSE(t.empty());
  EXPECT_LE(t.back(), NsToSeconds(imu_end) + 0.1 + 1e-6);
}

// Item: lidar.time_offset moving every scan past the IMU's end, or before its
// start: exit 2 with the counts of all scans and the offset named.
TEST_F(QuietFailureTest, TimeOffsetMovingEveryScanAwayFromTheImuIsNamed) {
  for (const char* offset : {"5", "-5"}) {
    const std::string out = dir_ + "/out_offset";
    const ToolRun r = Run(Bag(), out, std::string("--set lidar.time_offset=") + offset);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_TRUE(Contains(r.err, std::to_string(ScanCount()) + " scans read")) << r.err;
    EXPECT_TRUE(Contains(r.err, std::string("lidar.time_offset ") + offset + " s")) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// Item: point times all zero, or in milliseconds / microseconds where
// nanoseconds belong, stop the run; a span well under the period warns.
TEST_F(QuietFailureTest, BrokenPointTimesStopOrWarn) {
  for (const auto& [name, factor, what] :
       std::vector<std::tuple<std::string, double, std::string>>{
           {"times_zero", 0.0, "all zero"},
           {"times_ms", 1e-6, "not in nanoseconds"},
           {"times_us", 1e-3, "not in nanoseconds"}}) {
    const std::string out = dir_ + "/out_" + name;
    const ToolRun r = Run(WithPointTimesScaled(name, factor), out);
    EXPECT_EQ(r.exit_code, 2) << name << ": " << r.err;
    EXPECT_EQ(Lines(r.err), 1) << r.err;
    EXPECT_TRUE(Contains(r.err, "point times on lidar.topic")) << r.err;
    EXPECT_TRUE(Contains(r.err, what)) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
  const std::string out = dir_ + "/out_times_short";
  const ToolRun r = Run(WithPointTimesScaled("times_short", 0.3), out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(Contains(r.err, "lidar.point_time_span_warn")) << r.err;
  EXPECT_NEAR(Summary(out)["stats"]["reader"]["point_time_span_ratio"].get<double>(), 0.3, 0.02);
}

// Item: reading a ROS1 bag prints nothing from the ROS1 library's plugin
// lookup and writes nothing into the home folder (~/.ros/rospack_cache_*).
TEST_F(QuietFailureTest, Ros1BagReadsWithoutRospackWarningsOrFilesInHome) {
  const std::string home = dir_ + "/home";
  fs::create_directories(home);
  ToolRun r = RunToolWith("info --bag " + Bag(), dir_, "", "env -u ROS_HOME HOME=" + home);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  EXPECT_TRUE(Entries(home).empty());
  // A home folder that cannot hold ~/.ros (a file: not writable even for root).
  const std::string file_home = dir_ + "/home_file";
  test::WriteAll(file_home, "not a folder");
  const std::string out = dir_ + "/out_home";
  r = RunToolWith("run --bag " + Bag() + " --config " + Sensors() + " --out " + out +
                      " --set lidar.topic=/nope",
                  dir_, "", "env -u ROS_HOME HOME=" + file_home);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_FALSE(Contains(r.err, "rospack")) << r.err;
}

// Items: an MCAP file cut short. Cut inside its first chunk, the message says
// it is truncated (not "topic not in bag"); cut later, the run reads the part
// before the cut, exits 0 and marks the summary "truncated": true.
TEST_F(QuietFailureTest, TruncatedMcapIsNamedAndMarkedInTheSummary) {
  const std::string mcap = dir_ + "/rec.mcap";
  WriteCopy(mcap);
  const std::string bytes = ReadFile(mcap);
  const std::string tiny = dir_ + "/tiny.mcap", part = dir_ + "/part.mcap";
  test::WriteAll(tiny, bytes.substr(0, bytes.size() / 10));
  test::WriteAll(part, bytes.substr(0, bytes.size() * 7 / 10));
  ToolRun r = Run(tiny, dir_ + "/out_tiny");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "'" + tiny + "' is truncated")) << r.err;
  const std::string out = dir_ + "/out_part";
  r = Run(part, out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(Contains(r.err, "cut short")) << r.err;
  EXPECT_EQ(Summary(out)["truncated"], true);
  EXPECT_EQ(Summary(dir_ + "/clean")["truncated"], false);
}

// Item: IMU stamps all equal: the message names the repeated stamps.
TEST_F(QuietFailureTest, ImuStampsAllEqualAreNamedInTheMessage) {
  const std::string bag = dir_ + "/imu_zero.bag";
  WriteCopy(bag, nullptr, nullptr, kLidarTopic, "");
  int samples = 0;
  {
    rosbag::Bag b;
    b.open(bag, rosbag::bagmode::Append);
    for (const Message& m : *messages_) {
      if (!m.is_imu) continue;
      const ImuSample& s = m.imu;
      b.write(kImuTopic, test::RosTime(s.t_ns),
              test::ImuMsg(1, s.acc_imu.x(), s.acc_imu.y(), s.acc_imu.z(), s.gyro_imu.z()));
      ++samples;
    }
    b.close();
  }
  const ToolRun r = Run(bag, dir_ + "/out_imu_zero");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_TRUE(Contains(r.err, std::to_string(samples - 1) + " repeating the previous stamp"))
      << r.err;
}

// Item: a configuration file with a large unknown section names the key.
TEST_F(QuietFailureTest, LargeUnknownConfigSectionIsNamed) {
  std::string yaml = "lidar:\n  voxel_size: 0.5\nlidr_extra:\n";
  for (int i = 0; i < 12000; ++i) yaml += "  - " + std::to_string(i) + "\n";
  const std::string config = dir_ + "/big.yaml";
  test::WriteAll(config, yaml);
  const ToolRun r = Run(Bag(), dir_ + "/out_big", "--config " + config);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_TRUE(Contains(r.err, "lidr_extra: unknown key in " + config + ":3")) << r.err;
}

// Items: merge checks each chunk's trajectory against its chunk.json and
// takes a list after one --chunks; a rejected refine --resume leaves no
// new output folder.
TEST_F(QuietFailureTest, MergeChecksTheChunkTrajectoryAndRefineResumeLeavesNoFolder) {
  const std::string chunk = dir_ + "/chunk1";
  ToolRun r = RunToolWith("refine --bag " + Bag() + " --config " + Sensors() + " --init " +
                              Clean("trajectory.tum") + " --chunk 1 --of 1 --out " + chunk,
                          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // A list after one --chunks: the second folder is read as a chunk.
  r = RunToolWith("merge --chunks " + chunk + " " + dir_ + "/no_such_chunk --out " + dir_ + "/m",
                  dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(Contains(r.err, dir_ + "/no_such_chunk/chunk.json: no such file")) << r.err;
  // The chunk's trajectory cut short.
  const std::string tum = chunk + "/trajectory.tum";
  std::istringstream in(ReadFile(tum));
  std::string cut;
  int kept = 0;
  for (std::string line; kept < 15 && std::getline(in, line);) {
    cut += line + "\n";
    if (line[0] != '#') ++kept;
  }
  test::WriteAll(tum, cut);
  r = RunToolWith("merge --chunks " + chunk + " --out " + dir_ + "/m", dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(Contains(r.err, tum + " has 15 poses, but " + chunk + "/chunk.json records"))
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/m"));

  const std::string ck = dir_ + "/bad_checkpoint", out = dir_ + "/out_resume";
  fs::create_directories(ck);
  test::WriteAll(ck + "/refine.checkpoint", "not a checkpoint");
  r = RunToolWith("refine --bag " + Bag() + " --config " + Sensors() + " --init " +
                      Clean("trajectory.tum") + " --resume " + ck + " --out " + out,
                  dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(fs::exists(out)) << "a rejected resume must not create --out";
}

// Item: eval refuses an estimate whose stamps collapsed to one value.
TEST_F(QuietFailureTest, EvalRefusesCollapsedStamps) {
  const std::string est = dir_ + "/collapsed.tum";
  test::WriteAll(est, "1.7e+09 0 0 0 0 0 0 1\n1.7e+09 1 0 0 0 0 0 1\n1.7e+09 2 0 0 0 0 0 1\n");
  const ToolRun r = RunToolWith("eval --gt " + dir_ + "/data/tunnel_gt.tum --est " + est, dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(Lines(r.err), 1) << r.err;
  EXPECT_TRUE(Contains(r.err, est + ", line 3: time stamp 1.7e+09 is the third in a row")) << r.err;
}

}  // namespace
}  // namespace rvlio::badinput
