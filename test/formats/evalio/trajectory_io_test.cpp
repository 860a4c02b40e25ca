// TUM/KITTI readers and writer: round trips, exact stamps and bad input with
// the file and line in the message.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

const std::string kData = std::string(RVLIO_TEST_DATA) + "/";

class TempDir {
 public:
  TempDir() {
    char tmpl[] = "/tmp/rvlio_evalio_XXXXXX";
    path_ = ::mkdtemp(tmpl);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

Trajectory RandomTrajectory(std::mt19937& rng, size_t n) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_int_distribution<int64_t> dt(1, 200000000);
  Trajectory t(n);
  TimeNs stamp = 1305031102160407000LL;
  for (size_t i = 0; i < n; ++i) {
    stamp += dt(rng);
    t[i].t_ns = stamp;
    t[i].p_world_imu = Eigen::Vector3d(g(rng), g(rng), g(rng)) * 100.0;
    t[i].q_world_imu = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
  }
  return t;
}

void ExpectSamePoses(const Trajectory& a, const Trajectory& b, double tol_p, double tol_q) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns) << i;
    EXPECT_LT((a[i].p_world_imu - b[i].p_world_imu).norm(), tol_p) << i;
    EXPECT_LT(a[i].q_world_imu.angularDistance(b[i].q_world_imu), tol_q) << i;
  }
}

// Expects an error whose message contains every one of `parts`.
void ExpectError(const StatusOr<Trajectory>& r, const std::vector<std::string>& parts) {
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
  for (const std::string& p : parts)
    EXPECT_NE(r.status().message().find(p), std::string::npos)
        << "'" << p << "' not in: " << r.status().message();
}

TEST(ParseSeconds, ExactDecimalNanoseconds) {
  TimeNs t = 0;
  ASSERT_TRUE(ParseSecondsToNs("1305031102.160407", &t));
  EXPECT_EQ(t, 1305031102160407000LL);
  ASSERT_TRUE(ParseSecondsToNs("1311868163.8697", &t));
  EXPECT_EQ(t, 1311868163869700000LL);
  ASSERT_TRUE(ParseSecondsToNs("0.0000000015", &t));  // rounds half up
  EXPECT_EQ(t, 2);
  ASSERT_TRUE(ParseSecondsToNs("-1.5", &t));
  EXPECT_EQ(t, -1500000000LL);
  ASSERT_TRUE(ParseSecondsToNs(".25", &t));
  EXPECT_EQ(t, 250000000LL);
  ASSERT_TRUE(ParseSecondsToNs("42", &t));
  EXPECT_EQ(t, 42000000000LL);
  ASSERT_TRUE(ParseSecondsToNs("1.5e3", &t));
  EXPECT_EQ(t, 1500000000000LL);
  for (const char* bad : {"", ".", "-", "abc", "1.2.3", "1e400", "nan", "99999999999"})
    EXPECT_FALSE(ParseSecondsToNs(bad, &t)) << bad;
}

TEST(Tum, RoundTripKeepsStampsExactlyAndPosesToPrecision) {
  TempDir dir;
  std::mt19937 rng(1);
  const Trajectory t = RandomTrajectory(rng, 500);
  ASSERT_TRUE(WriteTum(dir.File("a.tum"), t, "written by a test\nsecond header line").ok());
  StatusOr<Trajectory> back = ReadTum(dir.File("a.tum"));
  ASSERT_TRUE(back.ok()) << back.status().message();
  ExpectSamePoses(t, *back, 1e-8, 1e-11);
  // The header comes first; no temporary file is left behind.
  std::ifstream in(dir.File("a.tum"));
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first, "# written by a test");
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) (void)e, ++files;
  EXPECT_EQ(files, 1);
}

TEST(Tum, FormatsNegativeAndSubsecondStamps) {
  StampedPose p;
  p.t_ns = -1500000000LL;
  EXPECT_EQ(FormatTumLine(p).rfind("-1.500000000 ", 0), 0u);
  p.t_ns = -5;
  EXPECT_EQ(FormatTumLine(p).rfind("-0.000000005 ", 0), 0u);
  p.t_ns = 7;
  EXPECT_EQ(FormatTumLine(p).rfind("0.000000007 ", 0), 0u);
}

TEST(Tum, ReadsTheEvoFixtureWithCommentsAndARepeatedStamp) {
  StatusOr<Trajectory> gt = ReadTum(kData + "evo/fr2_desk_groundtruth.txt");
  ASSERT_TRUE(gt.ok()) << gt.status().message();
  EXPECT_EQ(gt->size(), 20957u);  // 20960 lines minus 3 comments
  EXPECT_EQ(gt->front().t_ns, 1311868163869700000LL);
  EXPECT_NEAR(gt->front().p_world_imu.x(), -0.1357, 1e-15);
  // qx qy qz qw = 0.6453 -0.5498 0.3363 -0.4101, normalized.
  const Eigen::Vector4d q(0.6453, -0.5498, 0.3363, -0.4101);
  EXPECT_LT((gt->front().q_world_imu.coeffs() - q / q.norm()).norm(), 1e-15);
}

TEST(Tum, NormalizesNonUnitQuaternionsAndAcceptsTabsAndCrlf) {
  TempDir dir;
  WriteText(dir.File("q.tum"), "0.5\t1 2 3\t0 0 2 0\r\n0.6 1 2 3 0 0 0 3\r\n");
  StatusOr<Trajectory> t = ReadTum(dir.File("q.tum"));
  ASSERT_TRUE(t.ok()) << t.status().message();
  EXPECT_NEAR(t->at(0).q_world_imu.z(), 1.0, 1e-15);
  EXPECT_NEAR(t->at(1).q_world_imu.w(), 1.0, 1e-15);
  EXPECT_EQ(t->at(0).t_ns, 500000000);
}

TEST(Tum, BadInputNamesTheFileAndTheLine) {
  const std::string d = kData + "eval/";
  ExpectError(ReadTum(d + "missing_value.tum"),
              {"missing_value.tum", "line 5", "expected 8 values", "found 7"});
  ExpectError(ReadTum(d + "not_a_number.tum"), {"not_a_number.tum", "line 4", "'abc'"});
  ExpectError(ReadTum(d + "nan_value.tum"), {"nan_value.tum", "line 2", "'nan'"});
  ExpectError(ReadTum(d + "decreasing_stamps.tum"),
              {"decreasing_stamps.tum", "line 4", "earlier than the previous one (line 3)"});
  ExpectError(ReadTum(d + "zero_quaternion.tum"), {"zero_quaternion.tum", "line 2", "quaternion"});
  ExpectError(ReadTum(d + "empty.tum"), {"empty.tum", "contains no poses"});
  ExpectError(ReadTum(d + "does_not_exist.tum"),
              {"cannot open", "does_not_exist.tum", "No such file or directory"});
  ExpectError(ReadTum(d), {"is a directory"});
  ExpectError(ReadTrajectory(d + "unknown_format.txt"),
              {"unknown_format.txt", "line 1", "found 11"});
}

std::string KittiLine(const StampedPose& p) {
  const Eigen::Matrix3d R = p.q_world_imu.toRotationMatrix();
  char buf[512];
  std::snprintf(buf, sizeof(buf), "%.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e %.9e\n",
                R(0, 0), R(0, 1), R(0, 2), p.p_world_imu.x(), R(1, 0), R(1, 1), R(1, 2),
                p.p_world_imu.y(), R(2, 0), R(2, 1), R(2, 2), p.p_world_imu.z());
  return buf;
}

TEST(Kitti, ReadsPosesWithTimesFileOrAssumedRate) {
  TempDir dir;
  std::mt19937 rng(2);
  const Trajectory t = RandomTrajectory(rng, 40);
  std::string poses, times;
  for (const StampedPose& p : t) {
    poses += KittiLine(p);
    times += FormatTumLine(p).substr(0, FormatTumLine(p).find(' ')) + "\n";
  }
  WriteText(dir.File("poses.txt"), poses);
  WriteText(dir.File("times.txt"), times);
  StatusOr<Trajectory> k = ReadKitti(dir.File("poses.txt"), dir.File("times.txt"));
  ASSERT_TRUE(k.ok()) << k.status().message();
  ExpectSamePoses(t, *k, 1e-6, 1e-8);
  // Auto-detection picks KITTI from the 12 columns; without times: 10 Hz.
  StatusOr<Trajectory> auto_k = ReadTrajectory(dir.File("poses.txt"));
  ASSERT_TRUE(auto_k.ok()) << auto_k.status().message();
  ASSERT_EQ(auto_k->size(), t.size());
  EXPECT_EQ(auto_k->at(0).t_ns, 0);
  EXPECT_EQ(auto_k->at(13).t_ns, 1300000000LL);
  EXPECT_LT((auto_k->at(13).p_world_imu - t[13].p_world_imu).norm(), 1e-6);
  StatusOr<Trajectory> at20 = ReadKitti(dir.File("poses.txt"), "", 20.0);
  ASSERT_TRUE(at20.ok());
  EXPECT_EQ(at20->at(3).t_ns, 150000000LL);
}

TEST(Kitti, BadInput) {
  TempDir dir;
  ExpectError(ReadKitti(kData + "eval/kitti_not_rotation.txt"),
              {"kitti_not_rotation.txt", "line 2", "not a rotation"});
  std::mt19937 rng(3);
  const Trajectory t = RandomTrajectory(rng, 3);
  WriteText(dir.File("poses.txt"), KittiLine(t[0]) + KittiLine(t[1]) + KittiLine(t[2]));
  WriteText(dir.File("times.txt"), "0.0\n0.1\n");
  ExpectError(ReadKitti(dir.File("poses.txt"), dir.File("times.txt")),
              {"times.txt", "has 2 stamps", "has 3 poses"});
  WriteText(dir.File("times.txt"), "0.0\n0.2\n0.1\n");
  ExpectError(ReadKitti(dir.File("poses.txt"), dir.File("times.txt")),
              {"times.txt", "line 3", "earlier"});
  ExpectError(ReadKitti(dir.File("poses.txt"), "", 0.0), {"rate must be positive"});
  ExpectError(ReadTum(dir.File("poses.txt")), {"line 1", "expected 8 values", "found 12"});
}

}  // namespace
}  // namespace rvlio
