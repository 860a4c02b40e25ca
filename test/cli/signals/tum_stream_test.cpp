// TumStream: the partial trajectory is, line for line, what WriteTum writes.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/formats/trajectory_io.h"
#include "rvlio/formats/tum_stream.h"
#include "signals_util.h"

namespace rvlio::signals_test {
namespace {

TEST(TumStream, IsAPrefixOfWriteTumAtEveryPoseAndRemovesItself) {
  const std::string dir = testing_cli::MakeTempDir("rvlio_tum_stream");
  ASSERT_FALSE(dir.empty());
  Trajectory poses;
  for (int i = 0; i < 5; ++i) {
    StampedPose p;
    p.t_ns = 1700000000123456789 + i * 100000000LL;
    p.p_world_imu = Eigen::Vector3d(0.1 * i, -2.0 / 3.0 * i, 1e-7 * i);
    p.q_world_imu = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d(1, 2, 3).normalized()));
    poses.push_back(p);
  }
  ASSERT_TRUE(WriteTum(dir + "/full.tum", poses).ok());
  const std::string full = ReadFile(dir + "/full.tum");
  TumStream stream;
  ASSERT_TRUE(stream.Open(dir + "/partial.tum", 0.0).ok());  // sync on every pose
  for (const StampedPose& p : poses) {
    ASSERT_TRUE(stream.Append(p).ok());
    const std::string part = ReadFile(dir + "/partial.tum");
    EXPECT_EQ(full.compare(0, part.size(), part), 0) << part;
    StatusOr<Trajectory> parsed = ParseTumText(part, "partial.tum");
    ASSERT_TRUE(parsed.ok()) << parsed.status().message();
  }
  EXPECT_EQ(ReadFile(dir + "/partial.tum"), full);
  stream.Remove();
  EXPECT_FALSE(Exists(dir + "/partial.tum"));
  EXPECT_FALSE(stream.is_open());

  TumStream bad;
  const Status s = bad.Open(dir + "/no/such/folder/partial.tum");
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(dir + "/no/such/folder/partial.tum"), std::string::npos);
  EXPECT_FALSE(bad.Append(poses[0]).ok());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace rvlio::signals_test
