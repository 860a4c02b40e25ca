#pragma once
// The synthetic batch-refinement scene of the refine tests: noise-free scans
// of a box room taken along the closed-form motion of smoother_test_util.h
// with per-point times (motion distortion included), noise-free IMU samples,
// and a drifting, noisy initial trajectory.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "rvlio/lidar/extrinsics.h"
#include "rvlio/math/so3.h"
#include "rvlio/refine/refine.h"
#include "support/smoother_test_util.h"

namespace rvlio {
namespace refine_scene {

using Eigen::Vector3d;

constexpr TimeNs kT0 = 1000000000;       // first scan end
constexpr TimeNs kScanNs = 100000000;    // 10 Hz sweeps
inline const Vector3d kHalf(8.0, 6.0, 3.0);     // room half extents, m

inline const Pose3& ImuTLidar() {
  static const Pose3 T(test::Rz(0.3) * test::Rx(0.05), Vector3d(0.1, -0.05, 0.15));
  return T;
}

// First wall hit of a ray from o along unit d inside the box.
inline Vector3d HitBox(const Vector3d& o, const Vector3d& d) {
  double t_hit = 1e9;
  for (int i = 0; i < 3; ++i)
    if (std::abs(d(i)) > 1e-9) t_hit = std::min(t_hit, ((d(i) > 0 ? kHalf(i) : -kHalf(i)) - o(i)) / d(i));
  return o + t_hit * d;
}

// The time of return i of n in the sweep starting at t_start.
inline TimeNs ReturnTime(TimeNs t_start, int i, int n) { return t_start + (kScanNs * i) / (n - 1); }

// One sweep ending at t_end: n returns in random directions, each observed
// from the LiDAR pose at its own time; return i has intensity i + 0.5 and
// ring i % 16 (so a map point tells which return it is).
inline Scan SimulateScan(std::mt19937& rng, TimeNs t_end, int n) {
  Scan scan;
  scan.t_start_ns = t_end - kScanNs;
  scan.t_end_ns = t_end;
  scan.has_intensity = scan.has_ring = true;
  for (int i = 0; i < n; ++i) {
    LidarPoint p;
    p.t_ns = ReturnTime(scan.t_start_ns, i, n);
    p.intensity = static_cast<float>(i) + 0.5f;
    p.ring = static_cast<uint16_t>(i % 16);
    const Pose3 T_world_lidar = test::TruePose(p.t_ns).ToPose3() * ImuTLidar();
    const Vector3d d = test::RandomVector(rng, 1.0).normalized();
    const Vector3d hit = HitBox(T_world_lidar.t, T_world_lidar.R * d);
    p.p_lidar = (T_world_lidar.Inverse() * hit).cast<float>();
    scan.points.push_back(p);
  }
  return scan;
}

struct Scene {
  RefineInput input;
  std::vector<Pose3> truth;  // at the scan ends
};

// Initial trajectory: truth with a drift growing along the sequence
// (position and yaw/roll) plus white noise, all scaled by `perturbation`;
// the first pose exact.
inline Scene MakeScene(int scans, uint32_t seed, double perturbation = 1.0) {
  std::mt19937 rng(seed);
  Scene s;
  s.input.imu = test::SimulateImu(kT0 - 2 * kScanNs, kT0 + scans * kScanNs, 2500000);  // 400 Hz
  for (int k = 0; k < scans; ++k) {
    const TimeNs t = kT0 + k * kScanNs;
    s.input.scans.push_back(SimulateScan(rng, t, 1500));
    const Pose3 T = test::TruePose(t).ToPose3();
    s.truth.push_back(T);
    const double f = static_cast<double>(k) / scans;
    Pose3 P = T;
    if (k > 0) {
      const double a = perturbation;
      P.t += a * (f * Vector3d(0.25, -0.15, 0.1) + test::RandomVector(rng, 0.02));
      P.R = P.R * so3::Exp(a * (f * Vector3d(0.01, 0.0, 0.02) + test::RandomVector(rng, 0.003)));
    }
    s.input.init.push_back(StampedPose{t, P.t, Eigen::Quaterniond(P.R)});
  }
  return s;
}

inline RefineConfig Config() {
  RefineConfig c;
  c.T_imu_lidar = ImuTLidar();
  c.imu.gyro_noise_density = 1e-3;
  c.imu.accel_noise_density = 1e-2;
  c.imu.gyro_bias_random_walk = 1e-4;
  c.imu.accel_bias_random_walk = 1e-3;
  c.imu.gravity = 9.81;  // the closed-form motion's gravity; its start is not static
  c.rv.enabled = false;
  c.constraints.lidar_noise = 0.02;
  c.refine.rounds = 6;
  c.refine.threads = 2;
  return c;
}

}  // namespace refine_scene
}  // namespace rvlio
