#pragma once
// Alignment of an estimated trajectory onto the reference.
//
// Umeyama (1991) on positions only: find s, R, t minimizing
//   sum_i || y_i - (s R x_i + t) ||^2,   x = estimate, y = reference,
// with s = 1 for SE3. "origin" aligns the first matched pose only:
// T = T_ref_0 * T_est_0^-1. Applying a similarity to a pose scales and moves
// the position (p' = s R p + t) and rotates the orientation (q' = R q).
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"

namespace rvlio {

enum class AlignMode { kNone, kOrigin, kSe3, kSim3 };

const char* AlignModeName(AlignMode mode);  // "none" | "origin" | "se3" | "sim3"
StatusOr<AlignMode> ParseAlignMode(const std::string& name);

// p_ref = scale * R_ref_est p_est + t_ref_est.
struct Similarity3 {
  Eigen::Matrix3d R_ref_est = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_ref_est = Eigen::Vector3d::Zero();
  double scale = 1.0;

  Eigen::Vector3d operator*(const Eigen::Vector3d& p_est) const {
    return scale * (R_ref_est * p_est) + t_ref_est;
  }
  StampedPose Apply(const StampedPose& pose_est) const;
  Trajectory Apply(const Trajectory& trajectory_est) const;
};

// Umeyama's closed form. x_est and y_ref hold one point per column (same
// count, >= 1). Error when the problem has no unique solution: the
// cross-covariance has rank < 2 (e.g. all points on one line, or fewer than
// 3 points), or, with scale, the estimate has no spread.
StatusOr<Similarity3> Umeyama(const Eigen::Matrix3Xd& x_est, const Eigen::Matrix3Xd& y_ref,
                              bool with_scale);

// T = T_ref_0 * T_est_0^-1 from the first pose of each trajectory.
Similarity3 OriginAlignment(const StampedPose& ref0, const StampedPose& est0);
// The rigid alignment of whole poses: R_ref_est the chordal mean of
// R_ref_i R_est_i^T over the matched poses, t_ref_est the mean of
// p_ref_i - R_ref_est p_est_i. Unlike Umeyama on positions it is well
// conditioned on a straight path (the roll about the path comes from the
// orientations): what a map is moved by before it is compared with a
// reference cloud (compare and ablate with a reference map).
Similarity3 PoseAlignment(const Trajectory& ref_matched, const Trajectory& est_matched);

struct AlignOptions {
  double min_lateral_ratio = 1e-3;  // see EvalOptions (eval/options.h)
  size_t min_poses = 3;
};

struct AlignmentResult {
  AlignMode requested = AlignMode::kSe3;
  AlignMode used = AlignMode::kSe3;  // kOrigin after a fallback
  Similarity3 T_ref_est;
  std::vector<std::string> warnings;  // why a fallback happened
};

// Second over first principal standard deviation of the positions, i.e.
// sqrt(lambda_2 / lambda_1) of their centred covariance (0 for a line or a
// single point).
double LateralRatio(const Trajectory& trajectory);

// Aligns matched trajectories (pose k of each forms a pair; equal sizes,
// >= 1). SE3/Sim3 fall back to origin alignment when the reference is too
// short, collinear, or Umeyama is degenerate; the warnings say why.
AlignmentResult Align(const Trajectory& ref_matched, const Trajectory& est_matched, AlignMode mode,
                      const AlignOptions& options = AlignOptions());

}  // namespace rvlio
