#include "rvlio/imu/preintegration.h"

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Matrix96d = Eigen::Matrix<double, 9, 6>;
using Matrix93d = Eigen::Matrix<double, 9, 3>;

// Linearization of one interval of the discrete scheme (header comment):
//   x' = A x + Bg (n_g + d_bg) + Ba (n_a + d_ba),  x = [d_theta, d_v, d_p].
struct IntervalLinearization {
  Matrix9d A = Matrix9d::Identity();
  Matrix93d Bg = Matrix93d::Zero();
  Matrix93d Ba = Matrix93d::Zero();
};

// With DR = Exp(w h), dR1 = dR DR, ah_k = a_k - b_a:
//   d_theta' = DR^T d_theta - Jr(w h) h n_g                      (Forster Eq. 59)
//   d_a      = -(dR [ah0]x d_theta + dR1 [ah1]x d_theta') / 2 - (dR + dR1) n_a / 2
//   d_v'     = d_v + h d_a,     d_p' = d_p + h d_v + h^2 / 2 d_a.
IntervalLinearization Linearize(const Eigen::Matrix3d& dR, const Eigen::Matrix3d& dR1,
                                const Eigen::Vector3d& w_h, const Eigen::Vector3d& ah0,
                                const Eigen::Vector3d& ah1, double h) {
  const Eigen::Matrix3d DRt = so3::Exp(w_h).transpose();
  const Eigen::Matrix3d Jr_h = so3::Jr(w_h) * h;
  const Eigen::Matrix3d dR1_ah1 = dR1 * so3::Hat(ah1);
  // d_a as a function of d_theta, n_g and n_a.
  const Eigen::Matrix3d Aa_theta = -0.5 * (dR * so3::Hat(ah0) + dR1_ah1 * DRt);
  const Eigen::Matrix3d Aa_g = 0.5 * dR1_ah1 * Jr_h;
  const Eigen::Matrix3d Aa_a = -0.5 * (dR + dR1);
  const double h2 = 0.5 * h * h;
  IntervalLinearization L;
  using P = ImuPreintegration;
  L.A.block<3, 3>(P::kRot, P::kRot) = DRt;
  L.A.block<3, 3>(P::kVel, P::kRot) = h * Aa_theta;
  L.A.block<3, 3>(P::kPos, P::kRot) = h2 * Aa_theta;
  L.A.block<3, 3>(P::kPos, P::kVel) = h * Eigen::Matrix3d::Identity();
  L.Bg.block<3, 3>(P::kRot, 0) = -Jr_h;
  L.Bg.block<3, 3>(P::kVel, 0) = h * Aa_g;
  L.Bg.block<3, 3>(P::kPos, 0) = h2 * Aa_g;
  L.Ba.block<3, 3>(P::kVel, 0) = h * Aa_a;
  L.Ba.block<3, 3>(P::kPos, 0) = h2 * Aa_a;
  return L;
}

}  // namespace

ImuPreintegration::ImuPreintegration(const ImuNoise& noise, const Eigen::Vector3d& bg_lin,
                                     const Eigen::Vector3d& ba_lin)
    : noise_(noise), bg_lin_(bg_lin), ba_lin_(ba_lin) {}

ImuPreintegration ImuPreintegration::FromSamples(const std::vector<ImuSample>& samples,
                                                 TimeNs t_start_ns, TimeNs t_end_ns,
                                                 const ImuNoise& noise,
                                                 const Eigen::Vector3d& bg_lin,
                                                 const Eigen::Vector3d& ba_lin) {
  RVLIO_CHECK(!samples.empty());
  RVLIO_CHECK(t_end_ns >= t_start_ns);
  ImuPreintegration pre(noise, bg_lin, ba_lin);
  pre.knots_.reserve(samples.size() + 2);
  pre.Append(InterpolateImu(samples, t_start_ns));
  for (const ImuSample& s : samples)
    if (s.t_ns > t_start_ns && s.t_ns < t_end_ns) pre.Append(s);
  pre.Append(InterpolateImu(samples, t_end_ns));
  return pre;
}

void ImuPreintegration::Append(const ImuSample& m) {
  if (!knots_.empty()) {
    RVLIO_CHECK_MSG(m.t_ns >= knots_.back().t_ns, "IMU knots must be appended in time order");
    if (m.t_ns == knots_.back().t_ns) return;
    IntegrateInterval(knots_.back(), m);
  }
  knots_.push_back(m);
}

// One interval of the scheme in the header, then the error-state propagation
// of the covariance and of the bias Jacobians with the same linearization.
void ImuPreintegration::IntegrateInterval(const ImuSample& m0, const ImuSample& m1) {
  const double h = NsToSeconds(m1.t_ns - m0.t_ns);
  const Eigen::Vector3d w_h = (0.5 * (m0.gyro_imu + m1.gyro_imu) - bg_lin_) * h;
  const Eigen::Vector3d ah0 = m0.acc_imu - ba_lin_;
  const Eigen::Vector3d ah1 = m1.acc_imu - ba_lin_;
  const Eigen::Matrix3d dR = delta_.dR;
  const Eigen::Matrix3d dR1 = dR * so3::Exp(w_h);
  const Eigen::Vector3d a = 0.5 * (dR * ah0 + dR1 * ah1);

  const IntervalLinearization L = Linearize(dR, dR1, w_h, ah0, ah1, h);
  cov_ = L.A * cov_ * L.A.transpose() +
         L.Bg * noise_.GyroMeasurementCov(h) * L.Bg.transpose() +
         L.Ba * noise_.AccelMeasurementCov(h) * L.Ba.transpose();
  Matrix96d B;
  B << L.Bg, L.Ba;
  J_bias_ = L.A * J_bias_ + B;

  delta_.dp += delta_.dv * h + 0.5 * h * h * a;
  delta_.dv += a * h;
  delta_.dR = dR1;
  dt_ += h;
}

void ImuPreintegration::Reset() {
  delta_ = PreintegratedDelta();
  dt_ = 0.0;
  cov_.setZero();
  J_bias_.setZero();
}

void ImuPreintegration::Repropagate(const Eigen::Vector3d& bg_lin,
                                    const Eigen::Vector3d& ba_lin) {
  bg_lin_ = bg_lin;
  ba_lin_ = ba_lin;
  Reset();
  for (size_t k = 1; k < knots_.size(); ++k) IntegrateInterval(knots_[k - 1], knots_[k]);
}

bool ImuPreintegration::RepropagateIfBiasMoved(const Eigen::Vector3d& bg,
                                               const Eigen::Vector3d& ba, double max_dbg,
                                               double max_dba) {
  if ((bg - bg_lin_).norm() <= max_dbg && (ba - ba_lin_).norm() <= max_dba) return false;
  Repropagate(bg, ba);
  return true;
}

// Forster Eq. 44.
PreintegratedDelta ImuPreintegration::Corrected(const Eigen::Vector3d& bg,
                                                const Eigen::Vector3d& ba) const {
  const Eigen::Vector3d dbg = bg - bg_lin_;
  const Eigen::Vector3d dba = ba - ba_lin_;
  PreintegratedDelta d;
  d.dR = delta_.dR * so3::Exp(J_R_bg() * dbg);
  d.dv = delta_.dv + J_v_bg() * dbg + J_v_ba() * dba;
  d.dp = delta_.dp + J_p_bg() * dbg + J_p_ba() * dba;
  return d;
}

ImuKinematics ImuPreintegration::Predict(const ImuKinematics& x_i, const Eigen::Vector3d& bg,
                                         const Eigen::Vector3d& ba,
                                         const Eigen::Vector3d& g_world) const {
  const PreintegratedDelta d = Corrected(bg, ba);
  ImuKinematics x_j;
  x_j.t_ns = x_i.t_ns + (end_ns() - start_ns());
  x_j.R_world_imu = x_i.R_world_imu * d.dR;
  x_j.v_world_imu = x_i.v_world_imu + g_world * dt_ + x_i.R_world_imu * d.dv;
  x_j.p_world_imu =
      x_i.p_world_imu + x_i.v_world_imu * dt_ + 0.5 * dt_ * dt_ * g_world + x_i.R_world_imu * d.dp;
  return x_j;
}

}  // namespace rvlio
