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
#include "rvlio/map/voxel_map.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/math/pose.h"

namespace rvlio {

struct LocalizationOptions {
  double min_overlap = 0.3;        // share of a scan's points on reference planes to count as localized
  double align_radius_max = 2.0;   // m, first (coarsest) association radius of the start alignment
  double align_radius_min = 0.2;   // m, last (finest) radius; each stage halves the radius
  int align_iterations = 6;        // Gauss-Newton iterations per radius
  double min_start_overlap = 0.3;  // the aligned first scan must overlap the reference this much
  double max_start_distance = 10.0;  // m, a reference point must lie this close to the initial position
  double min_start_axis_constraints = 5.0;   // the aligned first scan must fix every translation axis this well
  bool trust_initial_pose = false;  // take the initial pose along an axis the first scan does not fix
  double search_step = 2.0;         // m, position grid of the global search (no initial pose)
  double search_yaw_step = 15.0;    // deg, yaw step of the global search
  int search_keep = 20;             // best grid candidates aligned in full
  double search_ambiguity = 0.03;   // a distinct candidate within this overlap of the best: ambiguous
  double reference_voxel_size = 0.5;  // m, voxel edge of the reference's search structure
  // k-NN search in the reference: the 27 voxels around the query, or exact
  // (map.neighbor_search's choices). A reference is complete around the
  // sensor, so the k nearest nearly always lie in those voxels (where the
  // working map, holding only what the flight has seen, often has them
  // farther: map.neighbor_search stays exact); measured in docs/survey.md.
  std::string reference_neighbor_search = "nearby";
  DeviationOptions deviation;       // deviation_m of map.pcd and deviation.csv

  template <class V>
  void Visit(V& v) {
    v.Field("min_overlap", min_overlap, Spec().Range(0.0, 1.0)
        .Help("share of a scan's points with a reference plane below which the scan is matched to the working map (out of the reference)"));
    v.Field("align_radius_max", align_radius_max, Spec().Unit("m").Range(0.05, 20.0)
        .Help("first association radius of the alignment of the first scan to the reference"));
    v.Field("align_radius_min", align_radius_min, Spec().Unit("m").Range(0.01, 20.0)
        .Help("last association radius of that alignment (the radius halves per stage)"));
    v.Field("align_iterations", align_iterations, Spec().Range(1, 100)
        .Help("Gauss-Newton iterations per radius of that alignment"));
    v.Field("min_start_overlap", min_start_overlap, Spec().Range(0.0, 1.0)
        .Help("the aligned first scan must have this share of its points on reference planes, else the run stops (exit 2)"));
    v.Field("max_start_distance", max_start_distance, Spec().Unit("m").Positive()
        .Help("the reference must have a point this close to the initial position, else it is taken to be in another frame or unit (exit 2)"));
    v.Field("min_start_axis_constraints", min_start_axis_constraints, Spec().Range(0.0, 1e9)
        .Help("the aligned first scan must hold its least-fixed translation direction d as well as this many constraints along d would (lidar_noise^2 / largest position variance), else the start is ambiguous along d (a featureless tunnel's axis) and the run stops (exit 2)"));
    v.Field("trust_initial_pose", trust_initial_pose,
            Spec().Help("go on from the initial pose along a direction the first scan does not fix, instead of stopping"));
    v.Field("search_step", search_step, Spec().Unit("m").Range(0.1, 100.0)
        .Help("global search without an initial pose: position grid step over the reference's free space"));
    v.Field("search_yaw_step", search_yaw_step, Spec().Unit("deg").Range(1.0, 90.0)
        .Help("global search: yaw step (roll and pitch come from gravity)"));
    v.Field("search_keep", search_keep, Spec().Range(1, 1000)
        .Help("global search: the best grid candidates (overlap at the candidate) aligned in full"));
    v.Field("search_ambiguity", search_ambiguity, Spec().Range(0.0, 1.0)
        .Help("global search: a candidate more than 1 m or 10 deg from the best with an overlap within this of the best's makes the start ambiguous (exit 2)"));
    v.Field("reference_voxel_size", reference_voxel_size, Spec().Unit("m").Range(0.01, 20.0)
        .Help("voxel edge of the reference's search structure for association (thinned as the working map: 20 points per voxel, 0.1 m apart)"));
    v.Field("reference_neighbor_search", reference_neighbor_search, Spec().Choices({"exact", "nearby"})
        .Help("k-nearest search in the reference: exact, or among the 27 voxels around the query (cheaper; exact whenever the k nearest lie there, which a complete reference makes likely)"));
    v.Section("deviation", deviation);
  }
  Status Validate() {
    if (Status s = ValidateFields(*this, "localization"); !s.ok()) return s;
    if (align_radius_min > align_radius_max)
      return Status::InvalidInput("localization.align_radius_min (" +
                                  std::to_string(align_radius_min) +
                                  ") must not exceed localization.align_radius_max");
    return Status::Ok();
  }
};

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

struct ReferenceAlignment {
  Pose3 T_ref_imu;   // the aligned pose
  double overlap = 0.0;  // share of the points with an accepted plane at the final radius
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

// Global search without an initial pose: candidate poses on a grid over the
// reference's free space near its surfaces (localization.search_step) and
// over yaw (search_yaw_step; roll and pitch of R_tilt, the gravity-aligned
// orientation of the estimator), each scored by the overlap of a subsample
// of the scan at the candidate; the search_keep best are aligned in full
// (AlignToReference). Returns the aligned candidates, best overlap first.
std::vector<ReferenceAlignment> SearchReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                                const Pose3& T_imu_lidar,
                                                const VoxelMap& reference,
                                                const Eigen::Matrix3d& R_tilt,
                                                const ConstraintOptions& constraints,
                                                const LocalizationOptions& options);

// Share of p_lidar's points with an accepted reference plane at T_ref_imu
// (the constraint options' radii).
double ReferenceOverlap(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_ref_imu,
                        const Pose3& T_imu_lidar, const VoxelMap& reference,
                        const ConstraintOptions& constraints);

}  // namespace rvlio
