#include "rvlio/degeneracy/degeneracy.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "rvlio/constraints/point_to_plane.h"

namespace rvlio {
namespace {

constexpr int kRot = 0;    // pose block: [dtheta, dp]
constexpr int kTrans = 3;

// A translation part counts as a weak translation direction when the held
// (unit, 6-dim) directions span it with at least this singular value: a pure
// rotation direction with a small lever-arm translation part is no
// translation direction.
constexpr double kMinTranslationShare = 0.5;

// Sorts the report's weak directions by the information along them, the
// weakest first, and fixes each sign (largest-magnitude component positive).
void SortWeakDirections(const Eigen::Matrix3d& H_tt, DegeneracyReport* r) {
  std::vector<std::pair<double, Eigen::Vector3d>> dirs;
  for (int i = 0; i < r->num_weak; ++i) {
    Eigen::Vector3d d = r->weak_dirs_world[i].normalized();
    Eigen::Index k = 0;
    d.cwiseAbs().maxCoeff(&k);
    if (d(k) < 0.0) d = -d;
    dirs.emplace_back(d.dot(H_tt * d), d);
  }
  std::sort(dirs.begin(), dirs.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 0; i < dirs.size(); ++i) r->weak_dirs_world[i] = dirs[i].second;
}

void AddHeld(const PoseVector6d& v, DegeneracyTreatment* t) {
  t->held_pose.col(t->num_held++) = v;
}

// The translation directions spanned by the held pose directions.
void WeakTranslationsFromHeld(const Eigen::Matrix3d& H_tt, DegeneracyTreatment* t) {
  DegeneracyReport& r = t->report;
  r.num_held = t->num_held;
  r.degenerate = t->num_held > 0;
  if (t->num_held == 0) return;
  const Eigen::MatrixXd parts = t->held_pose.block(kTrans, 0, 3, t->num_held);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(parts, Eigen::ComputeThinU);
  for (int i = 0; i < static_cast<int>(svd.singularValues().size()); ++i)
    if (svd.singularValues()(i) >= kMinTranslationShare)
      r.weak_dirs_world[r.num_weak++] = svd.matrixU().col(i);
  SortWeakDirections(H_tt, &r);
}

// Zhang et al. 2016: degenerate eigen-directions of the whole pose information.
void AnalyzeRemap(const DegeneracyOptions& o, const PoseMatrix6d& H, DegeneracyTreatment* t) {
  const Eigen::SelfAdjointEigenSolver<PoseMatrix6d> eig(H);
  for (int i = 0; i < 6; ++i)
    if (eig.eigenvalues()(i) < o.remap_min_eigenvalue) AddHeld(eig.eigenvectors().col(i), t);
  WeakTranslationsFromHeld(H.block<3, 3>(kTrans, kTrans), t);
}

// X-ICP: filtered contribution sums along the block's eigenvectors.
// rows: the unit contribution directions of one block (normals or rotation rows).
Eigen::Vector3d FilteredContributions(const std::vector<Eigen::Vector3d>& rows,
                                      const Eigen::Matrix3d& eigenvectors, double min_contribution) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& u : rows) {
    const Eigen::Vector3d c = (eigenvectors.transpose() * u).cwiseAbs();
    for (int k = 0; k < 3; ++k)
      if (c(k) >= min_contribution) sum(k) += c(k);
  }
  return sum;
}

// The unit translation and rotation parts of every usable constraint row.
void ContributionRows(const ConstraintList& constraints, const Pose3& T_world_imu,
                      const Pose3& T_imu_lidar, std::vector<Eigen::Vector3d>* trans,
                      std::vector<Eigen::Vector3d>* rot) {
  trans->reserve(constraints.size());
  rot->reserve(constraints.size());
  Eigen::Matrix<double, 1, 6> h;
  for (const Constraint& c : constraints) {
    PointToPlaneResidual(c, T_world_imu, T_imu_lidar, &h);
    if (!h.allFinite() || !(c.weight > 0.0)) continue;
    const Eigen::Vector3d h_p = h.segment<3>(kTrans).transpose();
    const Eigen::Vector3d h_r = h.segment<3>(kRot).transpose();
    if (h_p.norm() > 1e-12) trans->push_back(h_p.normalized());
    if (h_r.norm() > 1e-12) rot->push_back(h_r.normalized());
  }
}

void AnalyzeLocalizability(const DegeneracyOptions& o, const PoseMatrix6d& H,
                           const ConstraintList& constraints, const Pose3& T_world_imu,
                           const Pose3& T_imu_lidar, DegeneracyTreatment* t) {
  std::vector<Eigen::Vector3d> trans, rot;
  ContributionRows(constraints, T_world_imu, T_imu_lidar, &trans, &rot);
  const std::pair<int, double> blocks[] = {{kRot, o.localizability_rotation_min},
                                           {kTrans, o.localizability_translation_min}};
  for (const auto& [offset, min_sum] : blocks) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(H.block<3, 3>(offset, offset));
    const Eigen::Vector3d L = FilteredContributions(offset == kRot ? rot : trans,
                                                    eig.eigenvectors(),
                                                    o.localizability_min_contribution);
    for (int k = 0; k < 3; ++k) {
      if (L(k) >= min_sum) continue;
      PoseVector6d v = PoseVector6d::Zero();
      v.segment<3>(offset) = eig.eigenvectors().col(k);
      AddHeld(v, t);
    }
  }
  WeakTranslationsFromHeld(H.block<3, 3>(kTrans, kTrans), t);
}

// Schur complement of the block at `offset` (rotation or translation):
// the information on it with the other block marginalized.
Eigen::Matrix3d SchurBlock(const PoseMatrix6d& H, int offset) {
  const int other = offset == kRot ? kTrans : kRot;
  const Eigen::Matrix3d H_oo = H.block<3, 3>(other, other);
  const Eigen::Matrix3d H_bo = H.block<3, 3>(offset, other);
  const Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix3d> inv(H_oo);
  const Eigen::Matrix3d S = H.block<3, 3>(offset, offset) - H_bo * inv.solve(H_bo.transpose());
  return 0.5 * (S + S.transpose());
}

void AnalyzeRegularized(const DegeneracyOptions& o, const PoseMatrix6d& H, DegeneracyTreatment* t) {
  DegeneracyReport& r = t->report;
  for (int offset : {kRot, kTrans}) {
    const Eigen::Matrix3d S = SchurBlock(H, offset);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(S);
    const double floor = eig.eigenvalues()(2) / o.regularized_max_condition;
    if (offset == kTrans) r.condition_number = ConditionNumber(S);
    for (int k = 0; k < 3; ++k) {
      const double lambda = std::max(eig.eigenvalues()(k), 0.0);
      if (!(lambda < floor)) continue;
      const Eigen::Vector3d v = eig.eigenvectors().col(k);
      t->damping.block<3, 3>(offset, offset) += (floor - lambda) * v * v.transpose();
      t->damped_pose.block<3, 1>(offset, r.num_damped) = v;
      t->damped_amount(r.num_damped) = floor - lambda;
      r.max_damping = std::max(r.max_damping, floor - lambda);
      ++r.num_damped;
      if (offset == kTrans) r.weak_dirs_world[r.num_weak++] = v;
    }
  }
  r.degenerate = r.num_damped > 0;
  SortWeakDirections(H.block<3, 3>(kTrans, kTrans), &r);
}

}  // namespace

double ConditionNumber(const Eigen::Matrix3d& symmetric) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(symmetric, Eigen::EigenvaluesOnly);
  const double lo = eig.eigenvalues()(0), hi = eig.eigenvalues()(2);
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > 0.0))
    return std::numeric_limits<double>::quiet_NaN();
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

DegeneracyTreatment AnalyzeDegeneracy(const DegeneracyOptions& options,
                                      const PoseMatrix6d& pose_information,
                                      const ConstraintList& constraints, const Pose3& T_world_imu,
                                      const Pose3& T_imu_lidar) {
  DegeneracyTreatment t;
  t.report.method = options.method;
  const Eigen::Matrix3d H_tt = pose_information.block<3, 3>(kTrans, kTrans);
  t.report.condition_number = ConditionNumber(H_tt);
  if (!pose_information.allFinite()) return t;
  switch (options.method) {
    case DegeneracyMethod::kRemap:
      AnalyzeRemap(options, pose_information, &t);
      break;
    case DegeneracyMethod::kLocalizability:
      AnalyzeLocalizability(options, pose_information, constraints, T_world_imu, T_imu_lidar, &t);
      break;
    case DegeneracyMethod::kRegularized:
      AnalyzeRegularized(options, pose_information, &t);
      break;
    case DegeneracyMethod::kRv:
    case DegeneracyMethod::kNone:
      break;  // rv edits the constraint list (DegeneracyReportFromRv); none does nothing
  }
  return t;
}

DegeneracyReport DegeneracyReportFromRv(DegeneracyMethod method, const RvReport& rv,
                                        const Eigen::Matrix3d& translation_information) {
  DegeneracyReport r;
  r.method = method;
  r.condition_number = ConditionNumber(translation_information);
  if (method != DegeneracyMethod::kRv || !rv.active) return r;
  r.degenerate = true;
  r.num_weak = 1;
  r.weak_dirs_world[0] = rv.n_alpha;
  return r;
}

PoseMatrix6d ScanPoseInformation(const ConstraintList& constraints, const Pose3& T_world_imu,
                                 const Pose3& T_imu_lidar) {
  PoseMatrix6d H = PoseMatrix6d::Zero();
  Eigen::Matrix<double, 1, 6> h;
  for (const Constraint& c : constraints) {
    PointToPlaneResidual(c, T_world_imu, T_imu_lidar, &h);
    H.noalias() += c.weight * h.transpose() * h;
  }
  return H;
}

PoseMatrix6d DegeneracyPriorSqrtInformation(const DegeneracyOptions& options,
                                            const DegeneracyTreatment& t, bool* has_prior) {
  PoseMatrix6d S = PoseMatrix6d::Zero();
  int rows = 0;
  switch (options.method) {
    case DegeneracyMethod::kRemap:
    case DegeneracyMethod::kLocalizability:
      for (; rows < t.num_held; ++rows)
        S.row(rows) = std::sqrt(options.hold_information) * t.held_pose.col(rows).transpose();
      break;
    case DegeneracyMethod::kRegularized:
      for (; rows < t.report.num_damped; ++rows)
        S.row(rows) = std::sqrt(t.damped_amount(rows)) * t.damped_pose.col(rows).transpose();
      break;
    case DegeneracyMethod::kRv:
    case DegeneracyMethod::kNone:
      break;
  }
  if (has_prior != nullptr) *has_prior = rows > 0;
  return S;
}

LeastSquaresDegeneracy TreatLeastSquaresDegeneracy(const DegeneracyOptions& options,
                                                   const ConstraintList& constraints,
                                                   const Pose3& T_world_imu,
                                                   const Pose3& T_imu_lidar, double lidar_noise) {
  LeastSquaresDegeneracy out;
  out.report.method = options.method;
  if (options.method == DegeneracyMethod::kRv || options.method == DegeneracyMethod::kNone)
    return out;
  const DegeneracyTreatment t =
      AnalyzeDegeneracy(options, ScanPoseInformation(constraints, T_world_imu, T_imu_lidar),
                        constraints, T_world_imu, T_imu_lidar);
  out.report = t.report;
  out.sqrt_information = DegeneracyPriorSqrtInformation(options, t, &out.has_prior) / lidar_noise;
  out.num_held = t.num_held;
  out.held_pose = t.held_pose;
  return out;
}

void ProjectOutHeld(const DegeneracyTreatment& t, Eigen::Ref<PoseVector6d> dx_pose) {
  for (int i = 0; i < t.num_held; ++i) {
    const PoseVector6d v = t.held_pose.col(i);
    dx_pose -= v * v.dot(dx_pose);
  }
}

Eigen::VectorXd SolveHoldingDirections(const DegeneracyTreatment& t, const Eigen::MatrixXd& A,
                                       const Eigen::VectorXd& b) {
  const Eigen::Index n = A.rows();
  if (t.num_held == 0) return -A.ldlt().solve(b);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, t.num_held);
  C.topRows(6) = t.held_pose.leftCols(t.num_held);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(C);
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(n, n);
  const Eigen::MatrixXd Z = Q.rightCols(n - t.num_held);  // null space of C^T
  const Eigen::VectorXd y = (Z.transpose() * A * Z).ldlt().solve(Z.transpose() * b);
  return -Z * y;
}

}  // namespace rvlio
