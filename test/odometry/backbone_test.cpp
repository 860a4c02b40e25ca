// Both online backends through the one backbone (odometry/pipeline.h), in
// a program that links rvlio_odometry and nothing above it: test_odometry
// links that module only (test/CMakeLists.txt), so this file also checks that
// the odometry builds and links without refine. The input is synthetic (no
// simulator: rvlio_sim links the whole core): an IMU at rest, then a smooth
// turn and sway inside a box room, scanned by an ideal LiDAR.
#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "rvlio/common/time.h"
#include "rvlio/odometry/odometry.h"

namespace rvlio {
namespace {

constexpr double kRestS = 1.5;     // static start (imu.init_duration 1 s)
constexpr double kEndS = 4.0;      // the recording's length
constexpr double kOmega = 1.5;     // rad/s of the motion's cosines
constexpr TimeNs kImuPeriodNs = 2500000;   // 400 Hz
constexpr TimeNs kScanPeriodNs = 100000000;  // 10 Hz
const Eigen::Vector3d kG(0.0, 0.0, -9.81);
const Eigen::Vector3d kRoomHalf(6.0, 4.0, 2.5);  // m, box centred at the origin

// The platform at t: at rest until kRestS, then x, y and yaw follow
// a (1 - cos(w tau)) each (zero velocity at the start of the motion).
struct Motion {
  Eigen::Matrix3d R;
  Eigen::Vector3d p, v, a;
  double yaw_rate;
};

Motion At(double t_s) {
  const double tau = std::max(0.0, t_s - kRestS);
  const double f = 1.0 - std::cos(kOmega * tau);
  const double df = t_s > kRestS ? kOmega * std::sin(kOmega * tau) : 0.0;
  const double ddf = t_s > kRestS ? kOmega * kOmega * std::cos(kOmega * tau) : 0.0;
  const Eigen::Vector3d amplitude(0.8, 0.5, 0.0);  // m
  const double yaw_amplitude = 0.4;                // rad
  Motion m;
  m.R = Eigen::AngleAxisd(yaw_amplitude * f, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  m.p = amplitude * f;
  m.v = amplitude * df;
  m.a = amplitude * ddf;
  m.yaw_rate = yaw_amplitude * df;
  return m;
}

ImuSample Imu(TimeNs t_ns) {
  const Motion m = At(NsToSeconds(t_ns));
  ImuSample s;
  s.t_ns = t_ns;
  s.acc_imu = m.R.transpose() * (m.a - kG);
  s.gyro_imu = Eigen::Vector3d(0.0, 0.0, m.yaw_rate);
  return s;
}

// The distance along unit d from o (inside the room) to its walls.
double RangeToWalls(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double range = 1e9;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) continue;
    const double wall = d[i] > 0.0 ? kRoomHalf[i] : -kRoomHalf[i];
    range = std::min(range, (wall - o[i]) / d[i]);
  }
  return range;
}

// A sweep over (t_end - period, t_end]: each ray taken at its own time
// from the pose then (LiDAR frame = IMU frame).
Scan Sweep(TimeNs t_end_ns) {
  constexpr int kAzimuths = 180, kElevations = 16;
  Scan scan;
  scan.t_end_ns = t_end_ns;
  for (int a = 0; a < kAzimuths; ++a) {
    for (int e = 0; e < kElevations; ++e) {
      const int i = a * kElevations + e + 1;
      LidarPoint p;
      p.t_ns = t_end_ns - kScanPeriodNs + kScanPeriodNs * i / (kAzimuths * kElevations);
      const Motion m = At(NsToSeconds(p.t_ns));
      const double azimuth = 2.0 * M_PI * a / kAzimuths;
      const double elevation = -0.5 + 1.0 * e / (kElevations - 1);  // rad
      const Eigen::Vector3d d_lidar(std::cos(elevation) * std::cos(azimuth),
                                    std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const double range = RangeToWalls(m.p, m.R * d_lidar);
      p.p_lidar = (range * d_lidar).cast<float>();
      p.ring = static_cast<uint16_t>(e);
      scan.points.push_back(p);
    }
  }
  scan.t_start_ns = scan.points.front().t_ns;
  return scan;
}

// The recording through Odometry::Create, as RunRecording feeds it: the IMU
// up to each scan's end, then the scan, Poll; Finish at the end.
std::vector<ScanResult> RunOdometry(Backend backend, OdometryStats* stats) {
  OdometryOptions options;
  options.backend = backend;
  StatusOr<std::unique_ptr<Odometry>> odometry = Odometry::Create(options);
  EXPECT_TRUE(odometry.ok()) << odometry.status().message();
  if (!odometry.ok()) return {};
  Odometry& odo = **odometry;
  std::vector<ScanResult> results;
  TimeNs t_imu_ns = 0;
  for (TimeNs t_scan_ns = kScanPeriodNs; t_scan_ns <= SecondsToNs(kEndS);
       t_scan_ns += kScanPeriodNs) {
    for (; t_imu_ns <= t_scan_ns + kImuPeriodNs; t_imu_ns += kImuPeriodNs) odo.AddImu(Imu(t_imu_ns));
    odo.AddScan(Sweep(t_scan_ns));
    odo.Poll(&results);
  }
  odo.Finish(&results);
  EXPECT_TRUE(odo.status().ok());
  EXPECT_FALSE(odo.MapPoints().empty());
  *stats = odo.stats();
  return results;
}

class Backbone : public ::testing::TestWithParam<Backend> {};

TEST_P(Backbone, BothBackendsFollowTheMotionThroughTheOnePipeline) {
  OdometryStats stats;
  const std::vector<ScanResult> results = RunOdometry(GetParam(), &stats);
  ASSERT_GE(results.size(), 20u);
  EXPECT_EQ(stats.scans_processed, static_cast<int64_t>(results.size()));
  EXPECT_EQ(results.front().status, ScanStatus::kMapInit);
  int updated = 0;
  double worst_m = 0.0;
  for (size_t i = 0; i < results.size(); ++i) {
    const ScanResult& r = results[i];
    if (i > 0) {
      EXPECT_GT(r.t_ns, results[i - 1].t_ns);
    }
    updated += r.status == ScanStatus::kUpdated;
    const Motion truth = At(NsToSeconds(r.t_ns));
    worst_m = std::max(worst_m, (r.T_world_imu.t - truth.p).norm());
    // The state for the IMU-rate output (`rvlio live`): gravity as aligned
    // at rest, the IESKF's pose covariance.
    EXPECT_NEAR(r.g_world.norm(), 9.81, 0.05);
    EXPECT_EQ(r.pose_covariance_world.has_value(), GetParam() == Backend::kIeskf);
  }
  EXPECT_EQ(updated, static_cast<int>(results.size()) - 1);
  // The truth starts at the origin with identity yaw, as the static alignment
  // does (measured: 3.2 cm IESKF, 1.1 cm smoother at the worst scan).
  EXPECT_LT(worst_m, 0.05);
  const Motion end = At(NsToSeconds(results.back().t_ns));
  EXPECT_GT(end.p.norm(), 0.5);  // the motion was not nothing
}

INSTANTIATE_TEST_SUITE_P(Odometry, Backbone, ::testing::Values(Backend::kIeskf, Backend::kSmoother),
                         [](const ::testing::TestParamInfo<Backend>& info) {
                           return std::string(info.param == Backend::kIeskf ? "Ieskf" : "Smoother");
                         });

}  // namespace
}  // namespace rvlio
