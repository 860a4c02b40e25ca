#include "rvlio/eval/align.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "rvlio/common/text.h"

namespace rvlio {
namespace {

// Relative rank tolerance of the cross-covariance's singular values. evo
// uses machine epsilon; relative to the largest value is scale-free.
constexpr double kRankTol = 1e-12;

Eigen::Matrix3Xd Positions(const Trajectory& trajectory) {
  Eigen::Matrix3Xd p(3, trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) p.col(i) = trajectory[i].p_world_imu;
  return p;
}

// Why Umeyama should not be trusted for these matched poses; empty if fine.
std::string UmeyamaConcern(const Trajectory& ref, const AlignOptions& options) {
  if (ref.size() < options.min_poses)
    return "only " + std::to_string(ref.size()) + " matched poses (Umeyama needs at least " +
           std::to_string(options.min_poses) + ")";
  const double ratio = LateralRatio(ref);
  if (!(ratio >= options.min_lateral_ratio))
    return "reference positions are nearly collinear (lateral/axial spread " + FormatG(ratio, 3) +
           " < " + FormatG(options.min_lateral_ratio, 3) +
           "): the rotation about the line is unobservable";
  return "";
}

}  // namespace

const char* AlignModeName(AlignMode mode) {
  switch (mode) {
    case AlignMode::kNone:
      return "none";
    case AlignMode::kOrigin:
      return "origin";
    case AlignMode::kSe3:
      return "se3";
    case AlignMode::kSim3:
      return "sim3";
  }
  return "?";
}

StatusOr<AlignMode> ParseAlignMode(const std::string& name) {
  for (AlignMode m : {AlignMode::kNone, AlignMode::kOrigin, AlignMode::kSe3, AlignMode::kSim3})
    if (name == AlignModeName(m)) return m;
  return Status::InvalidInput("unknown alignment '" + name + "' (expected se3|sim3|origin|none)");
}

StampedPose Similarity3::Apply(const StampedPose& pose_est) const {
  StampedPose out = pose_est;
  out.p_world_imu = (*this) * pose_est.p_world_imu;
  out.q_world_imu = Eigen::Quaterniond(R_ref_est * pose_est.q_world_imu.toRotationMatrix());
  out.q_world_imu.normalize();
  return out;
}

Trajectory Similarity3::Apply(const Trajectory& trajectory_est) const {
  Trajectory out;
  out.reserve(trajectory_est.size());
  for (const StampedPose& p : trajectory_est) out.push_back(Apply(p));
  return out;
}

// Umeyama, "Least-squares estimation of transformation parameters between two
// point patterns", PAMI 1991, Eqs. (34)-(42):
//   Sigma_xy = 1/n sum (y_i - mu_y)(x_i - mu_x)^T = U D V^T,
//   S = diag(1, 1, det(U) det(V) < 0 ? -1 : 1),
//   R = U S V^T,  c = tr(D S) / sigma_x^2,  t = mu_y - c R mu_x.
StatusOr<Similarity3> Umeyama(const Eigen::Matrix3Xd& x_est, const Eigen::Matrix3Xd& y_ref,
                              bool with_scale) {
  RVLIO_CHECK(x_est.cols() == y_ref.cols() && x_est.cols() > 0);
  const double n = static_cast<double>(x_est.cols());
  const Eigen::Vector3d mu_x = x_est.rowwise().mean();
  const Eigen::Vector3d mu_y = y_ref.rowwise().mean();
  const Eigen::Matrix3Xd xc = x_est.colwise() - mu_x;
  const Eigen::Matrix3Xd yc = y_ref.colwise() - mu_y;
  const double sigma2_x = xc.squaredNorm() / n;
  const Eigen::Matrix3d cov_xy = yc * xc.transpose() / n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov_xy, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  if (!(d(1) > kRankTol * d(0)))
    return Status::InvalidInput(
        "Umeyama alignment is degenerate: the position cross-covariance has rank < 2");
  Eigen::Vector3d s_diag(1.0, 1.0, 1.0);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s_diag(2) = -1.0;
  Similarity3 T;
  T.R_ref_est = svd.matrixU() * s_diag.asDiagonal() * svd.matrixV().transpose();
  if (with_scale) {
    if (!(sigma2_x > 0.0))
      return Status::InvalidInput(
          "Umeyama Sim3 alignment is degenerate: the estimate has no spread");
    T.scale = d.dot(s_diag) / sigma2_x;
  }
  T.t_ref_est = mu_y - T.scale * (T.R_ref_est * mu_x);
  return T;
}

Similarity3 OriginAlignment(const StampedPose& ref0, const StampedPose& est0) {
  const Eigen::Matrix3d R_ref = ref0.q_world_imu.normalized().toRotationMatrix();
  const Eigen::Matrix3d R_est = est0.q_world_imu.normalized().toRotationMatrix();
  Similarity3 T;
  T.R_ref_est = R_ref * R_est.transpose();
  T.t_ref_est = ref0.p_world_imu - T.R_ref_est * est0.p_world_imu;
  return T;
}

Similarity3 PoseAlignment(const Trajectory& ref_matched, const Trajectory& est_matched) {
  Similarity3 T;
  const size_t n = std::min(ref_matched.size(), est_matched.size());
  if (n == 0) return T;
  Eigen::Matrix3d sum_R = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i)
    sum_R += ref_matched[i].q_world_imu.normalized().toRotationMatrix() *
             est_matched[i].q_world_imu.normalized().toRotationMatrix().transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum_R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  T.R_ref_est = svd.matrixU() * D * svd.matrixV().transpose();
  Eigen::Vector3d sum_t = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i)
    sum_t += ref_matched[i].p_world_imu - T.R_ref_est * est_matched[i].p_world_imu;
  T.t_ref_est = sum_t / static_cast<double>(n);
  return T;
}

double LateralRatio(const Trajectory& trajectory) {
  if (trajectory.size() < 2) return 0.0;
  const Eigen::Matrix3Xd p = Positions(trajectory);
  const Eigen::Matrix3Xd pc = p.colwise() - p.rowwise().mean();
  const Eigen::Matrix3d cov = pc * pc.transpose() / static_cast<double>(trajectory.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
  if (!(lambda(2) > 0.0)) return 0.0;
  return std::sqrt(std::max(lambda(1), 0.0) / lambda(2));
}

AlignmentResult Align(const Trajectory& ref_matched, const Trajectory& est_matched, AlignMode mode,
                      const AlignOptions& options) {
  RVLIO_CHECK(ref_matched.size() == est_matched.size() && !ref_matched.empty());
  AlignmentResult result;
  result.requested = result.used = mode;
  if (mode == AlignMode::kNone) return result;
  if (mode == AlignMode::kSe3 || mode == AlignMode::kSim3) {
    std::string concern = UmeyamaConcern(ref_matched, options);
    if (concern.empty()) {
      StatusOr<Similarity3> T =
          Umeyama(Positions(est_matched), Positions(ref_matched), mode == AlignMode::kSim3);
      if (T.ok()) {
        result.T_ref_est = *T;
        return result;
      }
      concern = T.status().message();
    }
    result.warnings.push_back(std::string(AlignModeName(mode)) + " alignment is ill-conditioned (" +
                              concern + "); fell back to origin alignment");
    result.used = AlignMode::kOrigin;
  }
  result.T_ref_est = OriginAlignment(ref_matched.front(), est_matched.front());
  return result;
}

}  // namespace rvlio
