#pragma once
// Localization in a fixed reference map (`rvlio run --map`, docs/survey.md).
//
// The reference is a point cloud in the reference frame (a static survey or
// an earlier rvlio map.pcd), held in its own search structure: a VoxelMap
// thinned as the working map is (voxels of localization.reference_voxel_size,
// at most 20 points each, 0.1 m apart), filled once and never changed
// afterwards. (The deviation uses the full cloud: odometry/deviation.h.) With a reference the odometry associates every
// scan with it (the same association template, point-to-plane constraints
// and RV pass as with the working map), so trajectory.tum and map.pcd come
// out in the reference frame. A scan whose overlap with the reference
// (share of its points with an accepted reference plane at the predicted
// pose) is below localization.min_overlap is associated with the working
// map instead: odometry in the reference frame, the working map being built
// from the estimated poses all along, so it continues from the last
// well-localized pose.
//
// Start: the first scan is aligned to the reference from the initial pose
// (IMU pose in the reference frame) by AlignToReference below: Gauss-Newton
// point-to-plane iterations with radii shrinking from
// localization.align_radius_max to align_radius_min (coarse to fine), so a
// start that is off by a metre and a few degrees is pulled in. The
// estimator's state is then moved into the reference frame as a whole (a
// rigid change of world frame: pose, velocity and gravity rotate together).
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "rvlio/common/options.h"
#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/constraints/options.h"
#include "rvlio/map/reference_map.h"
#include "rvlio/odometry/deviation.h"
#include "rvlio/odometry/localization_options.h"
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// What the odometry localizes in: the reference map (filled once, never
// changed) and the IMU pose in the reference frame at the first scan: the
// one pose of `initial_poses`, or the poses interpolated at the first scan's
// time (sorted by time). Both are in the reference's local frame (`origin`:
// the reference frame translated to near the map, math/local_origin.h), and
// so is everything the odometry estimates; the odometry reads `origin` only
// to print positions in the map's frame in its messages: whoever writes its
// results adds it back (api/run.cpp).
struct Localization {
  std::shared_ptr<const VoxelMap> reference;
  Trajectory initial_poses;
  LocalOrigin origin;
};

// Builds the reference's search structure from its points (reference frame,
// m; a cloud far from zero, e.g. in UTM, first into its local frame:
// ChooseLocalOrigin, math/local_origin.h, as LoadLocalization does).
std::shared_ptr<const VoxelMap> MakeReferenceMap(const std::vector<Eigen::Vector3d>& p_ref,
                                                 const LocalizationOptions& options);

// How closely a start's points must lie on their reference planes to count
// in its fit: this many constraints.lidar_noise.
constexpr double kStartFitNoises = 3.0;

struct ReferenceAlignment {
  Pose3 T_ref_imu;   // the aligned pose
  double overlap = 0.0;  // share of the points with an accepted plane at the final radius
  // Share of the points within kStartFitNoises * lidar_noise of an accepted
  // plane: what distinguishes the place from a look-alike (a start 2 m off
  // along a tunnel, a half turn, another world's map still overlap well).
  double fit = 0.0;
  // fit / overlap: the share of the matched points that lie on their planes
  // within the noise (near 1 at the right place in the right map).
  double Consistency() const { return overlap > 0.0 ? fit / overlap : 0.0; }
  int constraints = 0;
  // Gauss-Newton information (sum J^T J / lidar_noise^2) at the aligned pose,
  // columns [dtheta, dp] as PointToPlaneResidual's.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  // The least-fixed translation direction (reference frame, unit) and how
  // well it is fixed, in constraints fully along it: lidar_noise^2 over the
  // largest eigenvalue of the position covariance (information^-1, position
  // block). A featureless tunnel gives its axis and a value near 0.
  Eigen::Vector3d weakest_axis = Eigen::Vector3d::UnitX();
  double weakest_axis_constraints = 0.0;
};

// Aligns one deskewed scan (LiDAR frame) to the reference, coarse to fine,
// from T_ref_imu_guess. The constraint options give the plane tests; the
// radii and iteration counts come from `options`.
ReferenceAlignment AlignToReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                    const Pose3& T_imu_lidar, const VoxelMap& reference,
                                    const Pose3& T_ref_imu_guess,
                                    const ConstraintOptions& constraints,
                                    const LocalizationOptions& options);

// Global search: candidate poses on a grid over the reference's free space
// near its surfaces (localization.search_step; with `around`, only those
// within start_check_radius of around->t) and over yaw (search_yaw_step,
// starting at the yaw of R_start, whose roll and pitch every candidate
// keeps: the estimator's gravity-aligned orientation, or the initial pose's),
// each scored by the overlap of a subsample of the scan at the candidate;
// the search_keep best are aligned in full (AlignToReference). Returns the
// aligned candidates, best fit first.
std::vector<ReferenceAlignment> SearchReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                                const Pose3& T_imu_lidar,
                                                const VoxelMap& reference,
                                                const Eigen::Matrix3d& R_start,
                                                const ConstraintOptions& constraints,
                                                const LocalizationOptions& options,
                                                const Eigen::Vector3d* around = nullptr);

// The start in the reference, judged by one test whatever the platform does
// next: from T_ref_imu_guess (an initial pose; null: the global search from
// the orientation R_tilt), aligned, then refused (InvalidInput, one line
// naming `start_name` or the map) when it overlaps the reference less than
// min_start_overlap, leaves a translation direction unfixed
// (min_start_axis_constraints), fits nowhere near it as a scan of this place
// fits its map (the best candidate's Consistency below min_start_fit: the
// map), fits clearly better elsewhere (a distinct candidate's fit more than
// search_ambiguity above: the start is wrong) or as well elsewhere (within
// search_ambiguity: ambiguous). Distinct: more than 1 m or 10 deg apart.
// Positions in the messages are moved by `origin` into the map's frame as the
// user gave it (math/local_origin.h).
// With an initial pose and trust_initial_pose only the overlap and the fit
// of the aligned pose itself are checked.
StatusOr<ReferenceAlignment> FindStartInReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                                  const Pose3& T_imu_lidar,
                                                  const VoxelMap& reference,
                                                  const Pose3* T_ref_imu_guess,
                                                  const Eigen::Matrix3d& R_tilt,
                                                  const ConstraintOptions& constraints,
                                                  const LocalizationOptions& options,
                                                  const std::string& start_name,
                                                  const LocalOrigin& origin);

// Share of p_lidar's points with an accepted reference plane at T_ref_imu
// (the constraint options' radii).
double ReferenceOverlap(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_ref_imu,
                        const Pose3& T_imu_lidar, const VoxelMap& reference,
                        const ConstraintOptions& constraints);

}  // namespace rvlio
