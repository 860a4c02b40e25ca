#pragma once
// On-manifold IMU preintegration between two times (Forster et al., "On-
// Manifold Preintegration for Real-Time Visual-Inertial Odometry", T-RO 2017),
// for the smoother's IMU factor (docs/design.md "The backends").
//
// Deltas (IMU frame at t_i, independent of the state at t_i and of gravity):
//   dR = R_i^T R_j,  dv = R_i^T (v_j - v_i - g dt),  dp = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2)
// so that the state at t_j is predicted by
//   R_j = R_i dR,  v_j = v_i + g dt + R_i dv,  p_j = p_i + v_i dt + g dt^2 / 2 + R_i dp.
//
// Discretization: the same scheme as imu/integrator.h, so that the prediction
// equals imu::Integrate() up to rounding. Knots are t_i, the samples strictly
// inside (t_i, t_j) and t_j; the signal is linear between samples (held
// outside). On each interval of length h between knots (signals m0, m1):
//   w   = (w0 + w1)/2 - b_g,              dR' = dR Exp(w h)
//   a   = (dR (a0 - b_a) + dR' (a1 - b_a)) / 2
//   dp' = dp + dv h + a h^2 / 2,          dv' = dv + a h
//
// Error state (right perturbation on rotation, Forster Eq. 27-29):
//   dR_true = dR Exp(d_theta),  dv_true = dv + d_v,  dp_true = dp + d_p,
// ordered [d_theta, d_v, d_p] (offsets kRot, kVel, kPos). Noise model of one
// interval: one gyro and one accelerometer noise vector that perturbs the
// interval's averaged signal, with covariance sigma^2 / h each
// (ImuNoise::GyroMeasurementCov(h)); this reproduces the variance sigma^2 dt of
// independent per-sample noise (ImuNoise's convention) whatever the rate. The
// covariance and the bias Jacobians come from the exact linearization of the
// discrete scheme above, so they are consistent with it:
//   x' = A x + B_g (n_g + d_bg) + B_a (n_a + d_ba),    Cov' = A Cov A^T + B Q B^T,
//   J'  = A J + [B_g B_a]                              (J = d x / d [b_g, b_a]).
// The bias random walk is not part of the 9x9 covariance; the IMU factor adds
// it to its bias residuals.
//
// First-order bias correction (Forster Eq. 44) around the linearization biases
// (bg_lin, ba_lin) used in the integration:
//   dR(b) = dR Exp(J_R_bg (b_g - bg_lin)),  dv(b) = dv + J_v_bg d_bg + J_v_ba d_ba,
//   dp(b) = dp + J_p_bg d_bg + J_p_ba d_ba.
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/integrator.h"
#include "rvlio/imu/noise.h"

namespace rvlio {

using Matrix9d = Eigen::Matrix<double, 9, 9>;

// The preintegrated deltas at some biases.
struct PreintegratedDelta {
  Eigen::Matrix3d dR = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();  // m/s, IMU frame at t_i
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();  // m, IMU frame at t_i
};

class ImuPreintegration {
 public:
  static constexpr int kRot = 0;  // error-state offsets in the 9x9 covariance
  static constexpr int kVel = 3;
  static constexpr int kPos = 6;

  // An empty preintegration (dt = 0) linearized at the given biases
  // (gyro rad/s, accel m/s^2). Knots are added with Append().
  ImuPreintegration(const ImuNoise& noise, const Eigen::Vector3d& bg_lin,
                    const Eigen::Vector3d& ba_lin);

  // Preintegrates the signal of `samples` (sorted, non-empty) from t_start_ns
  // to t_end_ns >= t_start_ns, interpolating at both ends (integrator.h).
  static ImuPreintegration FromSamples(const std::vector<ImuSample>& samples, TimeNs t_start_ns,
                                       TimeNs t_end_ns, const ImuNoise& noise,
                                       const Eigen::Vector3d& bg_lin,
                                       const Eigen::Vector3d& ba_lin);

  // Adds the next knot: the signal at m.t_ns. The first knot sets the start
  // time; later knots must not be earlier than the last one (an equal time
  // adds a zero-length interval and is ignored).
  void Append(const ImuSample& m);

  // Re-integrates the stored knots with new linearization biases (resets the
  // deltas, covariance and Jacobians).
  void Repropagate(const Eigen::Vector3d& bg_lin, const Eigen::Vector3d& ba_lin);
  // Repropagate() only if |bg - bg_lin| > max_dbg (rad/s) or |ba - ba_lin| >
  // max_dba (m/s^2), where the first-order correction is no longer accurate.
  // Returns whether it re-integrated.
  bool RepropagateIfBiasMoved(const Eigen::Vector3d& bg, const Eigen::Vector3d& ba,
                              double max_dbg, double max_dba);

  // Deltas corrected to first order for biases (bg, ba) (see header comment).
  PreintegratedDelta Corrected(const Eigen::Vector3d& bg, const Eigen::Vector3d& ba) const;
  // The state at end_ns() from state x_i at start_ns(), using the deltas
  // corrected for (bg, ba).
  ImuKinematics Predict(const ImuKinematics& x_i, const Eigen::Vector3d& bg,
                        const Eigen::Vector3d& ba, const Eigen::Vector3d& g_world) const;

  const PreintegratedDelta& delta() const { return delta_; }
  const Eigen::Matrix3d& dR() const { return delta_.dR; }
  const Eigen::Vector3d& dv() const { return delta_.dv; }
  const Eigen::Vector3d& dp() const { return delta_.dp; }
  double dt() const { return dt_; }  // s
  TimeNs start_ns() const { return knots_.empty() ? 0 : knots_.front().t_ns; }
  TimeNs end_ns() const { return knots_.empty() ? 0 : knots_.back().t_ns; }
  // Covariance of [d_theta, d_v, d_p] from the white measurement noise.
  const Matrix9d& covariance() const { return cov_; }
  // Bias Jacobians (Forster Eq. 44 / App. B).
  // d[d_theta, d_v, d_p] / d[b_g, b_a] (9x6); d_theta does not depend on b_a.
  const Eigen::Matrix<double, 9, 6>& bias_jacobian() const { return J_bias_; }
  Eigen::Matrix3d J_R_bg() const { return J_bias_.block<3, 3>(kRot, 0); }
  Eigen::Matrix3d J_v_bg() const { return J_bias_.block<3, 3>(kVel, 0); }
  Eigen::Matrix3d J_v_ba() const { return J_bias_.block<3, 3>(kVel, 3); }
  Eigen::Matrix3d J_p_bg() const { return J_bias_.block<3, 3>(kPos, 0); }
  Eigen::Matrix3d J_p_ba() const { return J_bias_.block<3, 3>(kPos, 3); }
  const Eigen::Vector3d& bg_lin() const { return bg_lin_; }
  const Eigen::Vector3d& ba_lin() const { return ba_lin_; }
  const ImuNoise& noise() const { return noise_; }
  // The integrated signal: start, inner samples, end.
  const std::vector<ImuSample>& knots() const { return knots_; }

 private:
  void IntegrateInterval(const ImuSample& m0, const ImuSample& m1);
  void Reset();

  ImuNoise noise_;
  Eigen::Vector3d bg_lin_, ba_lin_;
  std::vector<ImuSample> knots_;
  PreintegratedDelta delta_;
  double dt_ = 0.0;
  Matrix9d cov_ = Matrix9d::Zero();
  Eigen::Matrix<double, 9, 6> J_bias_ = Eigen::Matrix<double, 9, 6>::Zero();
};

}  // namespace rvlio
