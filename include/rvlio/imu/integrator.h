#pragma once
// Deterministic, noise-free integration of the IMU kinematic state (R, p, v)
// from a stream of IMU samples, given biases and gravity. Used by the IESKF
// forward propagation and as the simulator's test oracle.
//
// Model (world frame z up, g_world e.g. (0, 0, -9.81)):
//   dR/dt = R Hat(omega_imu - b_g)
//   dv/dt = R (acc_imu - b_a) + g_world     (acc_imu = R^T (a_world - g_world))
//   dp/dt = v
// The measured signal is taken as linear in time between samples and held
// constant before the first / after the last sample, so the start and end
// times need not coincide with sample times. Each interval [t0, t1] between
// consecutive knots (start, sample times strictly inside, end) is integrated
// with the midpoint rule for rotation and the trapezoidal rule for the world
// acceleration (second order in the interval length):
//   R1 = R0 Exp(((w0 + w1)/2 - b_g) h)
//   a  = (R0 (a0 - b_a) + R1 (a1 - b_a)) / 2 + g_world
//   p1 = p0 + v0 h + a h^2 / 2,  v1 = v0 + a h,     h = t1 - t0 (s)
// h may be negative: integrating to an earlier time runs the same scheme
// backwards, and a forward run followed by a backward run over the same
// samples returns the start state exactly (up to rounding).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"

namespace rvlio {

struct ImuKinematics {
  TimeNs t_ns = 0;
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_imu = Eigen::Vector3d::Zero();  // m
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();  // m/s
};

// The IMU signal at t_ns: linear between the two samples around t_ns, the
// first / last sample outside their span. samples: non-empty, sorted by time.
ImuSample InterpolateImu(const std::vector<ImuSample>& samples, TimeNs t_ns);

// One interval from x (at x.t_ns, where the signal is m0) to m1.t_ns (where
// the signal is m1); m1.t_ns may be earlier than x.t_ns.
ImuKinematics IntegrateInterval(const ImuKinematics& x, const ImuSample& m0, const ImuSample& m1,
                                const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                                const Eigen::Vector3d& g_world);

// The state at t_end_ns (later or earlier than start.t_ns). samples: sorted by
// time, non-empty unless t_end_ns == start.t_ns.
ImuKinematics Integrate(const ImuKinematics& start, const std::vector<ImuSample>& samples,
                        TimeNs t_end_ns, const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                        const Eigen::Vector3d& g_world);

// The states at every knot: start, each sample time strictly between start
// and t_end_ns (in the direction of integration), and t_end_ns. The last
// element equals Integrate(...).
std::vector<ImuKinematics> IntegrateTrajectory(const ImuKinematics& start,
                                               const std::vector<ImuSample>& samples,
                                               TimeNs t_end_ns, const Eigen::Vector3d& bg,
                                               const Eigen::Vector3d& ba,
                                               const Eigen::Vector3d& g_world);

}  // namespace rvlio
