// Online extrinsic estimation in the IESKF (ieskf.estimate_extrinsics): the
// error-state Jacobian of the point-to-plane residual against numeric
// differences of the filter's own boxplus, and a filter run in a known room
// with a rotating IMU that recovers a perturbed extrinsic.
#include <random>

#include <gtest/gtest.h>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/ieskf/ieskf.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Vector3d RandomVector(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Eigen::Vector3d(u(*rng), u(*rng), u(*rng));
}

FilterState RandomState(std::mt19937* rng) {
  FilterState x;
  x.R_world_imu = so3::Exp(RandomVector(rng, 2.0));
  x.p_world_imu = RandomVector(rng, 20.0);
  x.v_world_imu = RandomVector(rng, 2.0);
  x.bg = RandomVector(rng, 0.01);
  x.ba = RandomVector(rng, 0.1);
  x.R_imu_lidar = so3::Exp(RandomVector(rng, 1.0));
  x.t_imu_lidar = RandomVector(rng, 0.3);
  return x;
}

// d r(x [+] d) / d d over all 24 error-state components, central differences.
Eigen::Matrix<double, 1, 24> NumericErrorStateJacobian(const Constraint& c, const FilterState& x) {
  const double h = 1e-6;
  Eigen::Matrix<double, 1, 24> J;
  for (int i = 0; i < 24; ++i) {
    Vector24d d = Vector24d::Zero();
    d(i) = h;
    const FilterState a = Boxplus(x, d), b = Boxplus(x, -d);
    J(i) = (PointToPlaneResidual(c, a.T_world_imu(), a.T_imu_lidar()) -
            PointToPlaneResidual(c, b.T_world_imu(), b.T_imu_lidar())) /
           (2 * h);
  }
  return J;
}

TEST(IeskfExtrinsic, ErrorStateJacobianMatchesNumericDifferences) {
  std::mt19937 rng(5);
  std::array<bool, 6> all;
  all.fill(true);
  const Eigen::Matrix<double, 24, 12> E = ErrorStateColumns(all);
  for (int trial = 0; trial < 300; ++trial) {
    const FilterState x = RandomState(&rng);
    Constraint c;
    c.p_lidar = RandomVector(&rng, 20.0);
    c.normal_world = RandomVector(&rng, 1.0).normalized();
    c.q_world = RandomVector(&rng, 30.0);
    Eigen::Matrix<double, 1, 12> h;
    PointToPlaneResidualWithExtrinsics(c, x.T_world_imu(), x.T_imu_lidar(), &h);
    const Eigen::Matrix<double, 1, 24> analytic = h * E.transpose();
    const Eigen::Matrix<double, 1, 24> numeric = NumericErrorStateJacobian(c, x);
    const double scale = 1.0 + numeric.norm();
    ASSERT_LT((analytic - numeric).norm() / scale, 1e-7) << "analytic " << analytic
                                                         << "\nnumeric  " << numeric;
    // Extrinsic rotation and translation columns, separately.
    EXPECT_LT((analytic.segment<3>(FilterState::kExtRot) -
               numeric.segment<3>(FilterState::kExtRot)).norm() / scale, 1e-7);
    EXPECT_LT((analytic.segment<3>(FilterState::kExtPos) -
               numeric.segment<3>(FilterState::kExtPos)).norm() / scale, 1e-7);
    // The residual does not depend on velocity, biases or gravity.
    EXPECT_LT(numeric.segment<9>(FilterState::kVel).norm(), 1e-6);
    EXPECT_LT(numeric.segment<3>(FilterState::kGrav).norm(), 1e-6);
  }
}

TEST(IeskfExtrinsic, FrozenAxesGetNoColumn) {
  std::array<bool, 6> free = {true, false, true, false, false, true};
  const Eigen::Matrix<double, 24, 12> E = ErrorStateColumns(free);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(E(FilterState::kExtRot + i, 6 + i), free[i] ? 1.0 : 0.0);
  EXPECT_TRUE((E.block<6, 6>(0, 0).isIdentity()));
  EXPECT_DOUBLE_EQ(E.sum(), 9.0);
}

// ---- Filter level: a box room known exactly (the map), an IMU rotating
// about all three axes inside it, instantaneous scans of the room's walls.

std::vector<Eigen::Vector3d> BoxRoomPoints(std::mt19937_64* rng) {
  const double hx = 6.0, hy = 4.0, hz = 3.0, step = 0.2, m = 0.25;
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);
  std::vector<Eigen::Vector3d> pts;
  for (double u = -hx + m; u <= hx - m; u += step)
    for (double s = -hz + m; s <= hz - m; s += step) {
      pts.emplace_back(u + jitter(*rng), -hy, s + jitter(*rng));
      pts.emplace_back(u + jitter(*rng), hy, s + jitter(*rng));
    }
  for (double u = -hx + m; u <= hx - m; u += step)
    for (double s = -hy + m; s <= hy - m; s += step) {
      pts.emplace_back(u + jitter(*rng), s + jitter(*rng), -hz);
      pts.emplace_back(u + jitter(*rng), s + jitter(*rng), hz);
    }
  for (double s = -hy + m; s <= hy - m; s += step)
    for (double z = -hz + m; z <= hz - m; z += step) {
      pts.emplace_back(-hx, s + jitter(*rng), z + jitter(*rng));
      pts.emplace_back(hx, s + jitter(*rng), z + jitter(*rng));
    }
  return pts;
}

// R(t) = A(t) B(t): a steady turn A = Exp(yaw_rate t e_z) and a rocking
// B = Exp(rock sin(rock_freq t) e_x), so the rotation axis changes over time
// (rotation about one fixed axis leaves the extrinsic translation along it
// unobservable). Body rate: B^T (yaw_rate e_z) + rock rock_freq cos(rock_freq t) e_x.
// A small Lissajous translation around the room's centre.
struct RotatingMotion {
  double yaw_rate = 0.6, rock = 0.4, rock_freq = 1.7;
  Eigen::Vector3d g_world{0.0, 0.0, -9.81};
  Eigen::Matrix3d B(double t) const {
    return so3::Exp(rock * std::sin(rock_freq * t) * Eigen::Vector3d::UnitX());
  }
  Eigen::Matrix3d R(double t) const {
    return so3::Exp(yaw_rate * t * Eigen::Vector3d::UnitZ()) * B(t);
  }
  Eigen::Vector3d w_imu(double t) const {
    return B(t).transpose() * (yaw_rate * Eigen::Vector3d::UnitZ()) +
           rock * rock_freq * std::cos(rock_freq * t) * Eigen::Vector3d::UnitX();
  }
  Eigen::Vector3d p(double t) const {
    return {0.5 * std::sin(0.8 * t), 0.4 * std::sin(1.1 * t), 0.2 * std::sin(0.5 * t)};
  }
  Eigen::Vector3d v(double t) const {
    return {0.4 * std::cos(0.8 * t), 0.44 * std::cos(1.1 * t), 0.1 * std::cos(0.5 * t)};
  }
  Eigen::Vector3d a(double t) const {
    return {-0.32 * std::sin(0.8 * t), -0.484 * std::sin(1.1 * t), -0.05 * std::sin(0.5 * t)};
  }
  ImuSample Sample(double t) const {
    ImuSample s;
    s.t_ns = SecondsToNs(t);
    s.gyro_imu = w_imu(t);
    s.acc_imu = R(t).transpose() * (a(t) - g_world);
    return s;
  }
};

struct ExtrinsicRunResult {
  double rot_err_deg = 0.0, pos_err_m = 0.0, imu_pos_err_m = 0.0;
  ExtrinsicExcitation excitation;
};

ExtrinsicRunResult RunRoom(const RotatingMotion& m, const Pose3& T_il_true, const Pose3& T_il_start,
                           bool estimate, double duration_s) {
  std::mt19937_64 rng(11);
  MapOptions mo;
  mo.voxel_size = 0.5;
  VoxelMap map(mo);
  map.Insert(BoxRoomPoints(&rng));
  const std::vector<Eigen::Vector3d> scan_world = BoxRoomPoints(&rng);

  RvOptions rv;
  rv.enabled = false;
  IeskfOptions o;
  o.estimate_extrinsics = estimate;
  o.max_iterations = 5;
  ImuOptions imu;
  Ieskf f(o, imu, ConstraintOptions(), rv);
  FilterState x0;
  x0.R_world_imu = m.R(0);
  x0.p_world_imu = m.p(0);
  x0.v_world_imu = m.v(0);
  x0.g_world = m.g_world;
  x0.R_imu_lidar = T_il_start.R;
  x0.t_imu_lidar = T_il_start.t;
  f.Initialize(x0, 0, m.Sample(0));

  std::vector<Eigen::Vector3d> scan_lidar;
  const int imu_per_scan = 20;  // 200 Hz IMU, 10 Hz scans
  for (int k = 1; k <= static_cast<int>(duration_s * 10); ++k) {
    for (int i = 1; i <= imu_per_scan; ++i) f.Propagate(m.Sample(((k - 1) * 20 + i) * 5e-3));
    const double t = k * 0.1;
    const Pose3 T_lidar_world = (Pose3(m.R(t), m.p(t)) * T_il_true).Inverse();
    scan_lidar.clear();
    for (size_t i = k % 5; i < scan_world.size(); i += 5) scan_lidar.push_back(T_lidar_world * scan_world[i]);
    f.Update([&](const FilterState& x, ConstraintList* out) {
      AssociationStats stats;
      ConstraintOptions co;
      co.max_plane_distance = 0.01;
      Associate(scan_lidar, x.T_world_imu(), x.T_imu_lidar(), map, co, out, &stats);
    });
    f.CountExcitationScan();
    f.ClearPoseHistory();
  }
  const FilterState& x = f.state();
  ExtrinsicRunResult r;
  r.rot_err_deg = so3::Log(T_il_true.R.transpose() * x.R_imu_lidar).norm() / kDeg;
  r.pos_err_m = (x.t_imu_lidar - T_il_true.t).norm();
  r.imu_pos_err_m = (x.p_world_imu - m.p(duration_s)).norm();
  r.excitation = f.extrinsic_excitation();
  return r;
}

const Pose3 kTrueExtrinsic(so3::Exp(Eigen::Vector3d(0.01, -0.02, 0.03)), Eigen::Vector3d(0.05, -0.03, 0.08));

Pose3 Perturbed(const Pose3& T, const Eigen::Vector3d& axis, double deg, const Eigen::Vector3d& dt) {
  return Pose3(T.R * so3::Exp(axis.normalized() * deg * kDeg), T.t + dt);
}

// The filter treats its map as exact and its pose absorbs most of a wrong
// extrinsic, so it converges slowly (docs/extrinsics.md): measured over this
// 12 s, 2 deg -> 1.12 deg, and the translation barely moves (4.9 cm of 5).
// The bounds keep the direction of travel; divergence (the former error-state
// layout bug) fails them by far.
TEST(IeskfExtrinsic, RotatingMotionReducesAPerturbedExtrinsicRotation) {
  const RotatingMotion m;
  const Pose3 start = Perturbed(kTrueExtrinsic, Eigen::Vector3d(1, -2, 1), 2.0,
                                Eigen::Vector3d(0.03, -0.03, 0.0277));  // 5 cm
  ASSERT_NEAR((start.t - kTrueExtrinsic.t).norm(), 0.05, 1e-3);
  const ExtrinsicRunResult r = RunRoom(m, kTrueExtrinsic, start, true, 12.0);
  EXPECT_LT(r.rot_err_deg, 1.5);
  EXPECT_LT(r.pos_err_m, 0.055);
  EXPECT_LT(r.imu_pos_err_m, 0.06);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(r.excitation.excited(i)) << "rotation axis " << i;
  EXPECT_GT(r.excitation.excited_fraction(), 0.5);
  RecordProperty("rot_err_deg", std::to_string(r.rot_err_deg));
  RecordProperty("pos_err_m", std::to_string(r.pos_err_m));
}

TEST(IeskfExtrinsic, ExactStartStaysExact) {
  const RotatingMotion m;
  const ExtrinsicRunResult r = RunRoom(m, kTrueExtrinsic, kTrueExtrinsic, true, 3.0);
  EXPECT_LT(r.rot_err_deg, 0.1);
  EXPECT_LT(r.pos_err_m, 0.005);
  const ExtrinsicRunResult off = RunRoom(m, kTrueExtrinsic, kTrueExtrinsic, false, 3.0);
  EXPECT_LT(r.imu_pos_err_m, off.imu_pos_err_m + 0.005);
}

}  // namespace
}  // namespace rvlio
