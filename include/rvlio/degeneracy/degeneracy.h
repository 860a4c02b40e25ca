#pragma once
// The degeneracy stage of one scan (one filter iteration): which pose
// directions the scan's point-to-plane constraints leave weak, and what the
// selected method does about it (docs/degeneracy.md).
//
// The pose block is the estimator's [dtheta, dp] columns: dtheta the right
// (body-frame) rotation perturbation, dp the world-frame position, so its
// translation directions are in the WORLD frame (the frame of RV's n_alpha).
//
//   remap           Zhang, Kaess, Singh (ICRA 2016): eigenvectors of the 6x6
//                   pose information with eigenvalue < remap_min_eigenvalue are
//                   degenerate; the increment is projected onto the others
//                   (V_f^-1 V_u with orthonormal V_f: I - sum_weak v v^T).
//   localizability  X-ICP (Tuna et al., T-RO 2023): per eigenvector v_k of the
//                   translation (rotation) information block, the sum of the
//                   constraints' contributions |n_i . v_k| (|unit(h_rot,i) . v_k|)
//                   above the filter threshold; a direction below the
//                   localizability threshold is held fixed: the update is
//                   solved with the equality constraint v_k . dx = 0.
//   regularized     DCReg-style: the rotation and translation Schur complements
//                   of the pose information; an eigenvalue below
//                   lambda_max / max_condition of its block is weak, and a
//                   Tikhonov term along that eigenvector alone lifts it to
//                   lambda_max / max_condition.
//   rv              the RV pass (rv/rv.h) on the constraint list, as before.
//   none            nothing.
#include <array>
#include <limits>

#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/degeneracy/options.h"
#include "rvlio/math/pose.h"
#include "rvlio/rv/rv.h"

namespace rvlio {

using PoseMatrix6d = Eigen::Matrix<double, 6, 6>;
using PoseVector6d = Eigen::Matrix<double, 6, 1>;

// The per-scan report, the same fields for every method.
struct DegeneracyReport {
  DegeneracyMethod method = DegeneracyMethod::kNone;
  bool degenerate = false;
  // Weak translation directions (world frame, unit), the weakest first;
  // num_weak of them are set (0..3).
  int num_weak = 0;
  std::array<Eigen::Vector3d, 3> weak_dirs_world{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                 Eigen::Vector3d::Zero()};
  // lambda_max / lambda_min of the translation information block (sigma = 1);
  // for regularized, of the translation Schur complement it judges. Infinite
  // when lambda_min <= 0, NaN when there was no information.
  double condition_number = std::numeric_limits<double>::quiet_NaN();
  // What the method did: pose directions (of 6) held fixed (remap,
  // localizability) or damped (regularized), and the largest damping added
  // (sigma = 1 information). rv: the RV report says what changed.
  int num_held = 0;
  int num_damped = 0;
  double max_damping = 0.0;
};

// The treatment the solve applies, with its report.
struct DegeneracyTreatment {
  DegeneracyReport report;
  int num_held = 0;                                  // columns of held_pose used
  PoseMatrix6d held_pose = PoseMatrix6d::Zero();     // orthonormal pose directions held
  PoseMatrix6d damping = PoseMatrix6d::Zero();       // added to the pose information (sigma = 1)
  // regularized: the damping as report.num_damped (direction, amount) pairs,
  // damping = sum_k damped_amount(k) damped_pose.col(k) damped_pose.col(k)^T
  // (the directions orthonormal).
  PoseMatrix6d damped_pose = PoseMatrix6d::Zero();
  PoseVector6d damped_amount = PoseVector6d::Zero();
};

// The pose block of sum_i w_i h_i^T h_i (sigma = 1) of a scan's constraints
// at the given poses: the rows of the IESKF's normal equations
// (PointToPlaneResidual), for the backends that build no normal equations of
// their own (the smoother, refine).
PoseMatrix6d ScanPoseInformation(const ConstraintList& constraints, const Pose3& T_world_imu,
                                 const Pose3& T_imu_lidar);

// A method's form in a nonlinear least-squares solve without an explicit
// increment (the smoother, refine; docs/degeneracy.md "Backends"): a prior
// on the scan's pose at an anchor (its predicted or initial value), whose
// residual is S (pose [-] anchor) with S the returned square-root
// information (sigma = 1, pose tangent [dtheta, dp]; rows sqrt(c_k) v_k^T,
// the unused rows zero):
//   remap, localizability  c_k = options.hold_information along every held
//                          direction v_k (a stiff prior: the pose stays at
//                          its anchor along them);
//   regularized            c_k = the Tikhonov damping along each damped
//                          eigenvector (the same term as in the IESKF);
//   rv, none               zero (no prior).
// has_prior (optional): whether any row is non-zero.
PoseMatrix6d DegeneracyPriorSqrtInformation(const DegeneracyOptions& options,
                                            const DegeneracyTreatment& t,
                                            bool* has_prior = nullptr);

// The degeneracy stage of the least-squares backends (the smoother, refine)
// for one scan: its constraints' pose information at T_world_imu
// (ScanPoseInformation) -> AnalyzeDegeneracy -> the prior
// (DegeneracyPriorSqrtInformation) in the scan's units, i.e. divided by
// lidar_noise (m). rv and none: no analysis, no prior; the report names the
// method.
struct LeastSquaresDegeneracy {
  DegeneracyReport report;
  bool has_prior = false;
  PoseMatrix6d sqrt_information = PoseMatrix6d::Zero();
  // remap, localizability: the held pose directions (DegeneracyTreatment),
  // for a backend whose form of the method is not a prior (the smoother's
  // remap: factors/pose_projected_factor.h).
  int num_held = 0;
  PoseMatrix6d held_pose = PoseMatrix6d::Zero();
};
LeastSquaresDegeneracy TreatLeastSquaresDegeneracy(const DegeneracyOptions& options,
                                                   const ConstraintList& constraints,
                                                   const Pose3& T_world_imu,
                                                   const Pose3& T_imu_lidar, double lidar_noise);

// Analyzes one scan. pose_information: the pose block of sum_i w_i h_i^T h_i
// (sigma = 1); constraints and the poses give the per-constraint rows for
// localizability (other methods do not read them).
DegeneracyTreatment AnalyzeDegeneracy(const DegeneracyOptions& options,
                                      const PoseMatrix6d& pose_information,
                                      const ConstraintList& constraints, const Pose3& T_world_imu,
                                      const Pose3& T_imu_lidar);

// The report of method rv (and none) from an RV report: degenerate = RV
// active, the weak direction = n_alpha.
DegeneracyReport DegeneracyReportFromRv(DegeneracyMethod method, const RvReport& rv,
                                        const Eigen::Matrix3d& translation_information);

// lambda_max / lambda_min of a symmetric 3x3 (see DegeneracyReport).
double ConditionNumber(const Eigen::Matrix3d& symmetric);

// remap: the pose part of an increment without its held components.
void ProjectOutHeld(const DegeneracyTreatment& t, Eigen::Ref<PoseVector6d> dx_pose);

// localizability: the minimizer of 1/2 dx^T A dx + b^T dx subject to
// held^T dx_pose = 0 (the pose is dx's first six entries), by the null-space
// method. Without held directions: -A^-1 b.
Eigen::VectorXd SolveHoldingDirections(const DegeneracyTreatment& t, const Eigen::MatrixXd& A,
                                       const Eigen::VectorXd& b);

}  // namespace rvlio
