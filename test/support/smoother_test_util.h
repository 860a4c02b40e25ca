#pragma once
// Shared helpers of the smoother tests: a closed-form 6-dof motion with its
// ideal IMU samples, random blocks, and numeric tangent-space Jacobians of a
// ceres::CostFunction through its blocks' manifolds.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ceres/cost_function.h>
#include <ceres/manifold.h>

#include "rvlio/common/types.h"
#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace test {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

inline const Vector3d& Gravity() {
  static const Vector3d g(0.0, 0.0, -9.81);
  return g;
}

struct Truth {
  Matrix3d R;
  Vector3d p, v, a_world, omega_imu;
};

inline Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitX()).toRotationMatrix(); }
inline Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitY()).toRotationMatrix(); }
inline Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Vector3d::UnitZ()).toRotationMatrix(); }

// Smooth closed-form motion inside a room centred at the origin:
// R = Rz(psi) Ry(theta) Rx(phi) with sinusoidal angles, sinusoidal position.
inline Truth Swing(double t) {
  const double psi = 0.9 * std::sin(0.8 * t), dpsi = 0.72 * std::cos(0.8 * t);
  const double th = 0.25 * std::sin(1.5 * t + 0.3), dth = 0.375 * std::cos(1.5 * t + 0.3);
  const double ph = 0.2 * std::cos(2.1 * t), dph = -0.42 * std::sin(2.1 * t);
  Truth x;
  x.R = Rz(psi) * Ry(th) * Rx(ph);
  x.omega_imu =
      Rx(ph).transpose() * (Ry(th).transpose() * Vector3d(0, 0, dpsi) + Vector3d(0, dth, 0)) +
      Vector3d(dph, 0, 0);
  x.p = Vector3d(3 * std::sin(0.6 * t), 2 * std::cos(0.4 * t), 0.4 * std::sin(1.3 * t));
  x.v = Vector3d(1.8 * std::cos(0.6 * t), -0.8 * std::sin(0.4 * t), 0.52 * std::cos(1.3 * t));
  x.a_world =
      Vector3d(-1.08 * std::sin(0.6 * t), -0.32 * std::cos(0.4 * t), -0.676 * std::sin(1.3 * t));
  return x;
}

inline PoseBlock TruePose(TimeNs t_ns) {
  const Truth x = Swing(NsToSeconds(t_ns));
  return PoseBlock(Eigen::Quaterniond(x.R), x.p);
}

inline SpeedBiasBlock TrueSpeedBias(TimeNs t_ns, const Vector3d& bg, const Vector3d& ba) {
  SpeedBiasBlock sb;
  sb.v_world_imu = Swing(NsToSeconds(t_ns)).v;
  sb.bg = bg;
  sb.ba = ba;
  return sb;
}

// Ideal (noise-free) samples every period_ns covering [t0, t1] with margin,
// constant biases added.
inline std::vector<ImuSample> SimulateImu(TimeNs t0, TimeNs t1, TimeNs period_ns,
                                          const Vector3d& bg = Vector3d::Zero(),
                                          const Vector3d& ba = Vector3d::Zero()) {
  std::vector<ImuSample> samples;
  for (TimeNs k = t0 / period_ns - 1; k <= t1 / period_ns + 2; ++k) {
    ImuSample s;
    s.t_ns = k * period_ns;
    const Truth x = Swing(NsToSeconds(s.t_ns));
    s.acc_imu = x.R.transpose() * (x.a_world - Gravity()) + ba;
    s.gyro_imu = x.omega_imu + bg;
    samples.push_back(s);
  }
  return samples;
}

inline Vector3d RandomVector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Vector3d(n(rng), n(rng), n(rng));
}

// n point-to-plane constraints with random points, normals, plane points
// and weights in [0, 2).
inline ConstraintList RandomConstraints(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> w(0.0, 2.0);
  ConstraintList list(n);
  for (Constraint& c : list) {
    c.p_lidar = RandomVector(rng, 10.0);
    c.normal_world = RandomVector(rng, 1.0).normalized();
    c.q_world = RandomVector(rng, 10.0);
    c.weight = w(rng);
  }
  return list;
}

inline PoseBlock RandomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
  if (q.norm() < 1e-3) q = Eigen::Quaterniond::Identity();
  return PoseBlock(q.normalized(), RandomVector(rng, 2.0));
}

inline SpeedBiasBlock RandomSpeedBias(std::mt19937& rng) {
  SpeedBiasBlock sb;
  sb.v_world_imu = RandomVector(rng, 1.0);
  sb.bg = RandomVector(rng, 0.01);
  sb.ba = RandomVector(rng, 0.1);
  return sb;
}

inline std::vector<double> ToVector(const PoseBlock& b) {
  std::vector<double> x(7);
  b.ToArray(x.data());
  return x;
}
inline std::vector<double> ToVector(const SpeedBiasBlock& b) {
  std::vector<double> x(9);
  b.ToArray(x.data());
  return x;
}

// Evaluates `cost` at `values`; optionally the ambient Jacobians (row-major).
inline Eigen::VectorXd EvaluateCost(const ceres::CostFunction& cost,
                                    const std::vector<std::vector<double>>& values,
                                    std::vector<RowMajorMatrix>* jacobians = nullptr) {
  std::vector<const double*> params;
  for (const auto& v : values) params.push_back(v.data());
  Eigen::VectorXd r(cost.num_residuals());
  std::vector<double*> J_ptrs;
  if (jacobians != nullptr) {
    jacobians->resize(values.size());
    for (size_t k = 0; k < values.size(); ++k) {
      (*jacobians)[k].resize(cost.num_residuals(), cost.parameter_block_sizes()[k]);
      J_ptrs.push_back((*jacobians)[k].data());
    }
  }
  const bool ok = cost.Evaluate(params.data(), r.data(), jacobians ? J_ptrs.data() : nullptr);
  if (!ok) r.setConstant(std::nan(""));
  return r;
}

// Max abs difference between the analytic chain (ambient Jacobian times the
// manifold's PlusJacobian) and central differences of the residual under
// x [+] h e_k in each block's tangent space, relative to max(1, |J|_max).
// manifolds[k] == nullptr: Euclidean.
inline double TangentJacobianError(const ceres::CostFunction& cost,
                                   const std::vector<std::vector<double>>& values,
                                   const std::vector<const ceres::Manifold*>& manifolds,
                                   double h = 1e-6) {
  std::vector<RowMajorMatrix> J_ambient;
  EvaluateCost(cost, values, &J_ambient);
  double worst = 0.0;
  for (size_t k = 0; k < values.size(); ++k) {
    const int as = static_cast<int>(values[k].size());
    const int ts = manifolds[k] ? manifolds[k]->TangentSize() : as;
    RowMajorMatrix plus = RowMajorMatrix::Identity(as, ts);
    if (manifolds[k]) manifolds[k]->PlusJacobian(values[k].data(), plus.data());
    const Eigen::MatrixXd analytic = J_ambient[k] * plus;
    Eigen::MatrixXd numeric(cost.num_residuals(), ts);
    for (int i = 0; i < ts; ++i) {
      std::vector<std::vector<double>> vp = values, vm = values;
      Eigen::VectorXd d = Eigen::VectorXd::Zero(ts);
      d(i) = h;
      if (manifolds[k]) {
        manifolds[k]->Plus(values[k].data(), d.data(), vp[k].data());
        d(i) = -h;
        manifolds[k]->Plus(values[k].data(), d.data(), vm[k].data());
      } else {
        vp[k][i] += h;
        vm[k][i] -= h;
      }
      numeric.col(i) = (EvaluateCost(cost, vp) - EvaluateCost(cost, vm)) / (2 * h);
    }
    const double scale = std::max(1.0, analytic.cwiseAbs().maxCoeff());
    worst = std::max(worst, (analytic - numeric).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

// Point-to-plane constraints of a scan taken at T_world_imu inside an
// axis-aligned box room centred at the origin (half extents `half`), with
// exact associations: n rays in random directions hit a wall; the constraint
// holds the point in the LiDAR frame, the wall's unit normal and another
// point of the same wall.
inline ConstraintList BoxRoomScan(std::mt19937& rng, const Pose3& T_world_imu,
                                  const Pose3& T_imu_lidar, int n,
                                  const Vector3d& half = Vector3d(8.0, 6.0, 3.0)) {
  const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
  const Pose3 T_lidar_world = T_world_lidar.Inverse();
  const Vector3d& o = T_world_lidar.t;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ConstraintList list;
  while (static_cast<int>(list.size()) < n) {
    const Vector3d d = RandomVector(rng, 1.0).normalized();
    double t_hit = 1e9;
    int axis = -1;
    for (int i = 0; i < 3; ++i) {
      if (std::abs(d(i)) < 1e-9) continue;
      const double t = ((d(i) > 0 ? half(i) : -half(i)) - o(i)) / d(i);
      if (t > 0 && t < t_hit) {
        t_hit = t;
        axis = i;
      }
    }
    if (axis < 0) continue;
    const Vector3d p_world = o + t_hit * d;
    Constraint c;
    c.p_lidar = T_lidar_world * p_world;
    c.normal_world = Vector3d::Unit(axis) * (d(axis) > 0 ? -1.0 : 1.0);  // pointing inwards
    c.q_world = p_world;
    for (int i = 0; i < 3; ++i)  // slide along the wall
      if (i != axis) c.q_world(i) = half(i) * u(rng);
    c.weight = 1.0;
    list.push_back(c);
  }
  return list;
}

}  // namespace test
}  // namespace rvlio
