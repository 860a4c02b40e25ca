// Regression tests for bugs the libFuzzer targets of fuzz/ found: each test
// replays the reproducing input (also kept as a seed under fuzz/corpus/) through
// the public API, and one runs it through the built tool.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "cli/cli_util.h"
#include "rvlio/config/config.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

using testing_cli::MakeTempDir;
using testing_cli::RunTool;
using testing_cli::ToolRun;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Nested aliases expanding to 10^9 values ("billion laughs"); `levels` deep.
std::string AliasExpansionYaml(int levels) {
  std::string yaml = "a0: &a0 [1,1,1,1,1,1,1,1,1,1]\n";
  for (int i = 1; i < levels; ++i) {
    yaml += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) yaml += (k ? ",*a" : "*a") + std::to_string(i - 1);
    yaml += "]\n";
  }
  return yaml;
}

// fuzz/corpus/config/recursive_alias: the alias refers to the sequence that
// contains it; converting the document recursed until the stack overflowed.
TEST(ConfigFuzzRegress, RecursiveAliasIsAnErrorNotAStackOverflow) {
  Configuration options;
  const Status s = ApplyYamlText(options, "a: &x [*x]\n", "loop.yaml");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_EQ(s.message(), "a in loop.yaml:1: nested deeper than 64 levels (a recursive alias?)");
}

TEST(ConfigFuzzRegress, RecursiveAliasInSetOverrideIsAnError) {
  Configuration options;
  const Status s = ApplyOverride(options, "rv.eps0=&x [*x]");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_TRUE(Contains(s.message(), "nested deeper than 64 levels")) << s.message();
}

// fuzz/corpus/config/alias_expansion: exponentially expanding aliases made the
// loader build 10^9 values (minutes of CPU, then out of memory).
TEST(ConfigFuzzRegress, ExponentialAliasExpansionIsBounded) {
  Configuration options;
  const Status s = ApplyYamlText(options, AliasExpansionYaml(9), "laughs.yaml");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kInvalidInput);
  EXPECT_TRUE(Contains(s.message(), "laughs.yaml:")) << s.message();
  // The bomb's top-level keys are not configuration keys: the expansion stops
  // at the value limit, and the first unknown key is what the message names.
  EXPECT_TRUE(Contains(s.message(), "a0: unknown key")) << s.message();
}

// The bounds leave ordinary anchors and aliases working.
TEST(ConfigFuzzRegress, OrdinaryAliasesStillLoad) {
  Configuration options;
  const Status s = ApplyYamlText(options,
                                 "lidar:\n  voxel_size: &v 0.7\nmap:\n  voxel_size: *v\n"
                                 "extrinsics:\n  imu_T_lidar:\n    translation: &t [0.1, 0.0, 0.05]\n",
                                 "anchors.yaml");
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_DOUBLE_EQ(options.lidar.voxel_size, 0.7);
  EXPECT_DOUBLE_EQ(options.map.voxel_size, 0.7);
  EXPECT_DOUBLE_EQ(options.extrinsics.imu_T_lidar.translation[2], 0.05);
}

// The whole `rvlio run --config` path: exit 2 with one line naming the file,
// where the unfixed tool died of a stack overflow.
TEST(ConfigFuzzRegress, RunWithRecursiveAliasConfigExitsTwo) {
  const std::string dir = MakeTempDir("rvlio_fuzzregress");
  const std::string config = dir + "/loop.yaml";
  std::ofstream(config) << "lidar:\n  topic: &x [*x]\n";
  const ToolRun r = RunTool("run --bag " + dir + "/missing.bag --config " + config + " --out " +
                                dir + "/out",
                            dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(Contains(r.err, "lidar in " + config + ":2: nested deeper than 64 levels"))
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  std::filesystem::remove_all(dir);
}

// fuzz/corpus/pointcloud2/float64_point_underflows_to_zero: a float64
// coordinate of 1e-50 passed the double zero test, then was stored as float
// 0: a (0, 0, 0) point kept in the scan although all-zero points are dropped
// (with lidar.min_range = 0 nothing else stopped it).
TEST(PointCloud2FuzzRegress, Float64PointThatRoundsToZeroIsDropped) {
  struct Point {
    double x, y, z;
    uint32_t t_ns;
  };
  const Point points[3] = {{1e-50, 0.0, -1e-60, 10}, {2.0, 0.0, 0.0, 20}, {0.0, 1e-30, 0.0, 30}};
  std::vector<uint8_t> data(3 * 28);
  for (int i = 0; i < 3; ++i) {
    std::memcpy(&data[i * 28 + 0], &points[i].x, 8);
    std::memcpy(&data[i * 28 + 8], &points[i].y, 8);
    std::memcpy(&data[i * 28 + 16], &points[i].z, 8);
    std::memcpy(&data[i * 28 + 24], &points[i].t_ns, 4);
  }
  PointCloud2View cloud;
  cloud.header_stamp_ns = 1000;
  cloud.height = 1;
  cloud.width = 3;
  cloud.point_step = 28;
  cloud.row_step = 84;
  cloud.fields = {{"x", 0, kPointFloat64, 1}, {"y", 8, kPointFloat64, 1},
                  {"z", 16, kPointFloat64, 1}, {"t", 24, kPointUint32, 1}};
  cloud.data = data.data();
  cloud.data_size = data.size();
  LidarOptions lidar;
  lidar.min_range = 0.0;
  DecodeStats stats;
  const StatusOr<Scan> scan = DecodePointCloud2(cloud, lidar, &stats);
  ASSERT_TRUE(scan.ok()) << scan.status().message();
  // 1e-50 is 0 as a float: dropped. 1e-30 is a normal float: kept (range
  // 1e-30 m >= min_range 0).
  ASSERT_EQ(scan->points.size(), 2u);
  EXPECT_FLOAT_EQ(scan->points[0].p_lidar.x(), 2.0f);
  EXPECT_EQ(scan->points[0].t_ns, 1020);
  EXPECT_FLOAT_EQ(scan->points[1].p_lidar.y(), 1e-30f);
  EXPECT_EQ(stats.invalid_points, 1);
  EXPECT_EQ(stats.raw_points, 3);
  EXPECT_EQ(stats.out_of_range_points, 0);
}

// fuzz/corpus/trajectory/tum_huge_quaternion: the norm of 1e200 components
// overflowed to inf, the "normalized" quaternion became zero, and the pose
// could not be written back (FormatTumLine printed 0 0 0 0).
TEST(TrajectoryFuzzRegress, TumHugeQuaternionComponentsNormalize) {
  const StatusOr<Trajectory> t = ParseTumText("0 0 0 0 1e200 1e200 1e200 1e200\n", "big.tum");
  ASSERT_TRUE(t.ok()) << t.status().message();
  ASSERT_EQ(t->size(), 1u);
  const Eigen::Vector4d q = (*t)[0].q_world_imu.coeffs();
  EXPECT_NEAR((q - Eigen::Vector4d::Constant(0.5)).norm(), 0.0, 1e-12);
  const StatusOr<Trajectory> again = ParseTumText(FormatTumLine((*t)[0]), "again.tum");
  ASSERT_TRUE(again.ok()) << again.status().message();
  EXPECT_NEAR(((*again)[0].q_world_imu.coeffs() - q).norm(), 0.0, 1e-11);
}

TEST(TrajectoryFuzzRegress, TumTinyQuaternionIsStillZero) {
  const StatusOr<Trajectory> t = ParseTumText("0 0 0 0 1e-200 0 0 1e-200\n", "tiny.tum");
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().message(), "tiny.tum, line 1: quaternion is zero");
}

// fuzz/corpus/trajectory/kitti_tiny_rate: i / rate_hz seconds overflowed the
// int64 ns conversion (undefined behaviour; UBSan float-cast-overflow).
TEST(TrajectoryFuzzRegress, KittiRateTooLowForThePosesIsAnError) {
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const StatusOr<Trajectory> t = ParseKittiText(identity + identity + identity, "k.txt",
                                                std::numeric_limits<double>::min());
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidInput);
  EXPECT_EQ(t.status().message(),
            "KITTI rate 2.22507e-308 Hz is too low for 3 poses: the stamps would overflow");
  // One pose needs no rate at all (t = 0), and 1e-9 Hz still fits 3 poses.
  const StatusOr<Trajectory> one =
      ParseKittiText(identity, "k.txt", std::numeric_limits<double>::min());
  ASSERT_TRUE(one.ok()) << one.status().message();
  EXPECT_EQ((*one)[0].t_ns, 0);
  const StatusOr<Trajectory> slow = ParseKittiText(identity + identity + identity, "k.txt", 1e-9);
  ASSERT_TRUE(slow.ok()) << slow.status().message();
  // 2 / 1e-9 s in double arithmetic: 2e18 ns to within 1 us.
  EXPECT_LT(std::llabs((*slow)[2].t_ns - 2000000000000000000), 1000);
}

// Found by CI's fuzz stage: a fuzzed rate of ~1e12 Hz gave every pose the
// stamp 0 ns. The KITTI reader took it, but the TUM file written from it did
// not read back (three equal stamps in a row).
TEST(TrajectoryFuzzRegress, KittiRateTooHighForNanosecondStampsIsAnError) {
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::string three = identity + identity + identity;
  const StatusOr<Trajectory> t = ParseKittiText(three, "k.txt", 1e12);
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidInput);
  EXPECT_EQ(t.status().message(),
            "KITTI rate 1e+12 Hz is too high: poses 1 and 2 would share the time stamp 0 ns "
            "(stamps are whole nanoseconds)");
  const StatusOr<Trajectory> detected = ParseTrajectoryText(three, "k.txt", 1.5e9);
  ASSERT_FALSE(detected.ok());
  EXPECT_EQ(detected.status().message(),
            "KITTI rate 1.5e+09 Hz is too high: poses 2 and 3 would share the time stamp 1 ns "
            "(stamps are whole nanoseconds)");
  // 1 GHz is one pose per nanosecond, and reads back as TUM.
  const StatusOr<Trajectory> ghz = ParseKittiText(three, "k.txt", 1e9);
  ASSERT_TRUE(ghz.ok()) << ghz.status().message();
  EXPECT_EQ((*ghz)[2].t_ns, 2);
  std::string tum;
  for (const auto& pose : *ghz) tum += FormatTumLine(pose);
  const StatusOr<Trajectory> back = ParseTumText(tum, "back.tum");
  ASSERT_TRUE(back.ok()) << back.status().message();
  EXPECT_EQ((*back)[2].t_ns, 2);
}

// Found by CI's fuzz stage: the quaternion of "0e200 1e260 1e000 1e200"
// (after scaling) has a rotation matrix with entries of ~1e-320; our KITTI
// writer prints them and strtod flags such subnormals with ERANGE, which the
// parser took for "not a finite number". Underflow is a finite value.
TEST(TrajectoryFuzzRegress, SubnormalAndUnderflowingValuesParse) {
  const std::string kitti =
      "-1 -1.999977734365366e-320 1e-60 0 1.999977734365366e-320 1 1e-260 0 -1e-60 1e-260 -1 0\n";
  const StatusOr<Trajectory> t = ParseKittiText(kitti, "sub.txt", 10.0);
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_NEAR(std::abs((*t)[0].q_world_imu.coeffs().dot(Eigen::Vector4d(0, 1, 0, 0))), 1.0, 1e-12);
  const StatusOr<Trajectory> tum = ParseTumText("0 1e-400 0 0 0 0 0 1\n", "under.tum");
  ASSERT_TRUE(tum.ok()) << tum.status().message();
  EXPECT_EQ((*tum)[0].p_world_imu.x(), 0.0);
  const StatusOr<Trajectory> over = ParseTumText("0 1e400 0 0 0 0 0 1\n", "over.tum");
  ASSERT_FALSE(over.ok());
}

// The text parsers and the file readers give the same results and messages.
TEST(TrajectoryFuzzRegress, TextParsersMatchFileReaders) {
  const std::string dir = MakeTempDir("rvlio_fuzzregress");
  const std::string tum = "# t x y z qx qy qz qw\n1.5 1 2 3 0 0 0 2\n\n2.5 1 2 4 0 0 1 1\n";
  const std::string path = dir + "/a.tum";
  std::ofstream(path) << tum;
  const StatusOr<Trajectory> from_file = ReadTum(path);
  const StatusOr<Trajectory> from_text = ParseTumText(tum, path);
  ASSERT_TRUE(from_file.ok() && from_text.ok());
  ASSERT_EQ(from_file->size(), 2u);
  ASSERT_EQ(from_text->size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ((*from_file)[i].t_ns, (*from_text)[i].t_ns);
    EXPECT_EQ((*from_file)[i].p_world_imu, (*from_text)[i].p_world_imu);
    EXPECT_EQ((*from_file)[i].q_world_imu.coeffs(), (*from_text)[i].q_world_imu.coeffs());
  }
  EXPECT_EQ((*from_text)[1].t_ns, 2500000000);
  const std::string bad = "1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n";
  std::ofstream(path) << bad;
  EXPECT_EQ(ReadTrajectory(path).status().message(), ParseTrajectoryText(bad, path).status().message());
  EXPECT_EQ(ParseTrajectoryText(bad, path).status().message(),
            path + ", line 2: time stamp 0.5 is earlier than the previous one (line 1); stamps "
                   "must not decrease");
  // KITTI with a times text: one stamp per pose.
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const StatusOr<Trajectory> k = ParseKittiText(identity + identity, "k.txt", "0.25\n0.75\n", "t.txt");
  ASSERT_TRUE(k.ok()) << k.status().message();
  EXPECT_EQ((*k)[1].t_ns, 750000000);
  EXPECT_EQ(ParseKittiText(identity + identity, "k.txt", "0.25\n", "t.txt").status().message(),
            "times file 't.txt' has 1 stamps but 'k.txt' has 2 poses");
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio
