// OpenSensorStream with --start: the reader starts a little before the
// window (a receive-time range) instead of reading the recording from its
// start, and delivers exactly what a full read filtered by the window rules
// gives, for ROS1, MCAP and db3, with the lidar.time_offset that makes the
// start check fail (read from the start) and ones that pass.
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cli/cli_util.h"
#include "rvlio/formats/sensor_stream.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

struct Message {
  char kind;
  TimeNs t_ns;  // IMU stamp or scan end, on the IMU clock
  size_t points;
  bool operator==(const Message& o) const {
    return kind == o.kind && t_ns == o.t_ns && points == o.points;
  }
};

struct Read {
  std::vector<Message> messages;
  int64_t invalid_points = 0;  // reader stats after the last message taken
};

// Everything `reader` delivers; with `until_ns`, stops after the last message
// not later than it (a full read's view of a window's end).
Read ReadEverything(SensorBagReader* reader, TimeNs until_ns = -1) {
  Read r;
  ImuSample imu;
  Scan scan;
  for (;;) {
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    EXPECT_TRUE(m.ok()) << m.status().message();
    if (!m.ok() || *m == SensorMessage::kEnd) break;
    const bool is_imu = *m == SensorMessage::kImu;
    const Message msg{is_imu ? 'i' : 's', is_imu ? imu.t_ns : scan.t_end_ns,
                      is_imu ? 0 : scan.points.size()};
    if (until_ns >= 0 && msg.t_ns > until_ns) break;
    r.messages.push_back(msg);
    r.invalid_points = reader->stats().invalid_points;
  }
  if (until_ns < 0) r.invalid_points = reader->stats().invalid_points;
  return r;
}

class WindowSkipTest : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing_cli::MakeTempDir("rvlio_window_skip");
    ASSERT_FALSE(dir_.empty());
    for (const std::string format : {"bag", "mcap", "db3"}) {
      const testing_cli::ToolRun sim = testing_cli::SimulateTunnel(
          dir_ + "/" + format, 5, 12, dir_, "--set lidar.columns=128 --format " + format);
      ASSERT_EQ(sim.exit_code, 0) << sim.err;
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Recording(const std::string& format) {
    return dir_ + "/" + format + "/tunnel." + format;
  }
  static std::string dir_;
};
std::string WindowSkipTest::dir_;

TEST_P(WindowSkipTest, DeliversWhatAFullReadGivesTheWindow) {
  const std::string path = Recording(GetParam());
  ReaderOptions io;
  io.reader_thread = false;
  ImuOptions imu;
  // 0 and -0.5 s: the start check passes; +4 s moves every scan end past the
  // window start, so the check fails and the recording is read from its start.
  for (const double time_offset_s : {0.0, -0.5, 4.0}) {
    for (const ReadWindow& window : {ReadWindow{5.0, 2.0}, ReadWindow{6.05, 0.3},
                                     ReadWindow{3.5, 0.0}}) {
      SCOPED_TRACE("time_offset " + std::to_string(time_offset_s) + " s, --start " +
                   std::to_string(window.start_s) + " --duration " +
                   std::to_string(window.duration_s));
      LidarOptions lidar;
      lidar.type = "ouster";
      lidar.time_offset = time_offset_s;
      auto full = OpenSensorStream(path, lidar, imu, ReadWindow(), io);
      auto windowed = OpenSensorStream(path, lidar, imu, window, io);
      ASSERT_TRUE(full.ok()) << full.status().message();
      ASSERT_TRUE(windowed.ok()) << windowed.status().message();
      const Read all = ReadEverything(full->get());
      ASSERT_FALSE(all.messages.empty());
      // The window rules of sensor_stream.h on the full read.
      const TimeNs start_ns = all.messages.front().t_ns + SecondsToNs(window.start_s);
      const TimeNs end_ns = window.duration_s > 0.0 ? start_ns + SecondsToNs(window.duration_s)
                                                    : std::numeric_limits<TimeNs>::max();
      std::vector<Message> want;
      for (const Message& m : all.messages) {
        if (m.t_ns > end_ns) break;
        if (m.t_ns >= start_ns - (m.kind == 'i' ? SecondsToNs(kImuLeadInS) : 0))
          want.push_back(m);
      }
      ASSERT_FALSE(want.empty());
      const Read got = ReadEverything(windowed->get());
      EXPECT_EQ(got.messages, want);
      // Without the time offset the scans before the window were not decoded:
      // fewer dropped points counted than a full read up to the window's end;
      // with +4 s the recording was read from its start: at least as many.
      auto until_end = OpenSensorStream(path, lidar, imu, ReadWindow(), io);
      ASSERT_TRUE(until_end.ok());
      const int64_t full_invalid = ReadEverything(until_end->get(), want.back().t_ns).invalid_points;
      if (time_offset_s == 0.0) {
        EXPECT_LT(got.invalid_points, full_invalid);
      }
      if (time_offset_s == 4.0) {
        EXPECT_GE(got.invalid_points, full_invalid);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Storages, WindowSkipTest, ::testing::Values("bag", "mcap", "db3"));

}  // namespace
}  // namespace rvlio
