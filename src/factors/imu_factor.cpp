#include "rvlio/factors/imu_factor.h"

#include <utility>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/math/so3.h"
#include "rvlio/factors/manifolds.h"

namespace rvlio {
namespace {

using Matrix15x6 = Eigen::Matrix<double, 15, 6>;
using Matrix15x9 = Eigen::Matrix<double, 15, 9>;
using RowMajor15x6 = Eigen::Matrix<double, 15, 6, Eigen::RowMajor>;
using RowMajor15x9 = Eigen::Matrix<double, 15, 9, Eigen::RowMajor>;

// S with S^T S = Sigma^-1 through the eigendecomposition Sigma = V L V^T,
// S = L^-1/2 V^T, with eigenvalues floored relative to the largest (a
// near-singular covariance, e.g. a very short interval, stays finite).
Matrix15d SqrtInformation(const Matrix15d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Matrix15d> eig(0.5 * (covariance + covariance.transpose()));
  const Vector15d lambda = eig.eigenvalues();
  RVLIO_CHECK_MSG(lambda.maxCoeff() > 0.0, "IMU factor covariance is zero (noise densities?)");
  const double floor = 1e-14 * lambda.maxCoeff();
  const Vector15d inv_sqrt = lambda.cwiseMax(floor).cwiseSqrt().cwiseInverse();
  return inv_sqrt.asDiagonal() * eig.eigenvectors().transpose();
}

Matrix15d FactorCovariance(const ImuPreintegration& pre) {
  Matrix15d cov = Matrix15d::Zero();
  cov.topLeftCorner<9, 9>() = pre.covariance();
  cov.block<3, 3>(ImuFactor::kBg, ImuFactor::kBg) = pre.noise().GyroBiasWalkCov(pre.dt());
  cov.block<3, 3>(ImuFactor::kBa, ImuFactor::kBa) = pre.noise().AccelBiasWalkCov(pre.dt());
  return cov;
}

}  // namespace

ImuFactor::ImuFactor(ImuPreintegration preintegration, const Eigen::Vector3d& g_world)
    : preintegration_(std::move(preintegration)), g_world_(g_world) {
  RVLIO_CHECK_MSG(preintegration_.dt() > 0.0, "IMU factor over an empty interval");
  covariance_ = FactorCovariance(preintegration_);
  sqrt_information_ = SqrtInformation(covariance_);
}

// Tangent Jacobians (derivation: right perturbation R Exp(phi), so
// (R Exp(phi))^T x ~= R^T x + Hat(R^T x) phi, and Log(E Exp(e)) ~= Log(E) +
// JrInv(Log E) e):
//   d r_R / d phi_i = -JrInv(r_R) R_j^T R_i,      d r_R / d phi_j = JrInv(r_R),
//   d r_R / d b_g,i = -JrInv(r_R) Exp(r_R)^T Jr(J_R_bg d_bg) J_R_bg,
//   d r_v / d phi_i = Hat(R_i^T (v_j - v_i - g dt)),
//   d r_p / d phi_i = Hat(R_i^T (p_j - p_i - v_i dt - g dt^2 / 2)),
//   d r_v / d v_i = -R_i^T,  d r_v / d v_j = R_i^T,  d r_p / d v_i = -R_i^T dt,
//   d r_p / d p_i = -R_i^T,  d r_p / d p_j = R_i^T,
//   d r_v / d b_i = -[J_v_bg J_v_ba],  d r_p / d b_i = -[J_p_bg J_p_ba],
//   d r_b / d b_i = -I,  d r_b / d b_j = I.
Vector15d ImuFactor::Residual(const PoseBlock& pose_i, const SpeedBiasBlock& sb_i,
                              const PoseBlock& pose_j, const SpeedBiasBlock& sb_j,
                              Eigen::Matrix<double, 15, 6>* J_pose_i,
                              Eigen::Matrix<double, 15, 9>* J_sb_i,
                              Eigen::Matrix<double, 15, 6>* J_pose_j,
                              Eigen::Matrix<double, 15, 9>* J_sb_j) const {
  const ImuPreintegration& pre = preintegration_;
  const double dt = pre.dt();
  const Eigen::Matrix3d Ri = pose_i.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d Rj = pose_j.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d RiT = Ri.transpose();
  const PreintegratedDelta d = pre.Corrected(sb_i.bg, sb_i.ba);
  const Eigen::Vector3d dv_world = sb_j.v_world_imu - sb_i.v_world_imu - g_world_ * dt;
  const Eigen::Vector3d dp_world = pose_j.p_world_imu - pose_i.p_world_imu -
                                   sb_i.v_world_imu * dt - 0.5 * dt * dt * g_world_;
  const Eigen::Matrix3d E = d.dR.transpose() * RiT * Rj;
  Vector15d r;
  r.segment<3>(kR) = so3::Log(E);
  r.segment<3>(kV) = RiT * dv_world - d.dv;
  r.segment<3>(kP) = RiT * dp_world - d.dp;
  r.segment<3>(kBg) = sb_j.bg - sb_i.bg;
  r.segment<3>(kBa) = sb_j.ba - sb_i.ba;

  const Eigen::Matrix3d JrInv_r = so3::JrInv(r.segment<3>(kR));
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  constexpr int kRot = PoseBlock::kRot, kTrans = PoseBlock::kTrans;
  constexpr int kVel = SpeedBiasBlock::kVel, kGb = SpeedBiasBlock::kBg, kAb = SpeedBiasBlock::kBa;
  if (J_pose_i != nullptr) {
    Matrix15x6& J = *J_pose_i;
    J.setZero();
    J.block<3, 3>(kR, kRot) = -JrInv_r * Rj.transpose() * Ri;
    J.block<3, 3>(kV, kRot) = so3::Hat(RiT * dv_world);
    J.block<3, 3>(kP, kRot) = so3::Hat(RiT * dp_world);
    J.block<3, 3>(kP, kTrans) = -RiT;
  }
  if (J_sb_i != nullptr) {
    Matrix15x9& J = *J_sb_i;
    J.setZero();
    const Eigen::Vector3d dbg = sb_i.bg - pre.bg_lin();
    J.block<3, 3>(kR, kGb) =
        -JrInv_r * E.transpose() * so3::Jr(pre.J_R_bg() * dbg) * pre.J_R_bg();
    J.block<3, 3>(kV, kVel) = -RiT;
    J.block<3, 3>(kV, kGb) = -pre.J_v_bg();
    J.block<3, 3>(kV, kAb) = -pre.J_v_ba();
    J.block<3, 3>(kP, kVel) = -RiT * dt;
    J.block<3, 3>(kP, kGb) = -pre.J_p_bg();
    J.block<3, 3>(kP, kAb) = -pre.J_p_ba();
    J.block<3, 3>(kBg, kGb) = -I;
    J.block<3, 3>(kBa, kAb) = -I;
  }
  if (J_pose_j != nullptr) {
    Matrix15x6& J = *J_pose_j;
    J.setZero();
    J.block<3, 3>(kR, kRot) = JrInv_r;
    J.block<3, 3>(kP, kTrans) = RiT;
  }
  if (J_sb_j != nullptr) {
    Matrix15x9& J = *J_sb_j;
    J.setZero();
    J.block<3, 3>(kV, kVel) = RiT;
    J.block<3, 3>(kBg, kGb) = I;
    J.block<3, 3>(kBa, kAb) = I;
  }
  return r;
}

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals,
                         double** jacobians) const {
  const PoseBlock pose_i = PoseBlock::FromArray(parameters[0]);
  const SpeedBiasBlock sb_i = SpeedBiasBlock::FromArray(parameters[1]);
  const PoseBlock pose_j = PoseBlock::FromArray(parameters[2]);
  const SpeedBiasBlock sb_j = SpeedBiasBlock::FromArray(parameters[3]);
  const bool want = jacobians != nullptr;
  Matrix15x6 J_pose_i, J_pose_j;
  Matrix15x9 J_sb_i, J_sb_j;
  const Vector15d r =
      Residual(pose_i, sb_i, pose_j, sb_j, want && jacobians[0] ? &J_pose_i : nullptr,
               want && jacobians[1] ? &J_sb_i : nullptr, want && jacobians[2] ? &J_pose_j : nullptr,
               want && jacobians[3] ? &J_sb_j : nullptr);
  Eigen::Map<Vector15d> residual(residuals);
  residual = sqrt_information_ * r;
  if (!want) return true;
  if (jacobians[0] != nullptr) {
    const RowMajor15x6 J = sqrt_information_ * J_pose_i;
    PoseTangentToAmbientJacobian(parameters[0], J, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<RowMajor15x9> J(jacobians[1]);
    J = sqrt_information_ * J_sb_i;
  }
  if (jacobians[2] != nullptr) {
    const RowMajor15x6 J = sqrt_information_ * J_pose_j;
    PoseTangentToAmbientJacobian(parameters[2], J, jacobians[2]);
  }
  if (jacobians[3] != nullptr) {
    Eigen::Map<RowMajor15x9> J(jacobians[3]);
    J = sqrt_information_ * J_sb_j;
  }
  return true;
}

}  // namespace rvlio
