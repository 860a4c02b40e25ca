#pragma once
// Survey ties of a refinement (docs/control.md): control marks under the
// device at rest (stop-and-go), wall targets seen by scans, GNSS fixes. Each
// is a PositionTie: a point rigidly attached to the IMU (p_imu_point), at
// one time, measured in the world frame of the refinement (the survey frame,
// moved into its local frame by the caller), with a square-root information
// and a robust kernel. One implementation for the three kinds: the
// PositionFactor (factors/position_factor.h).
//
// Before the refinement, the initial trajectory is carried into the survey
// frame by FitYawTranslation: both frames are gravity-aligned (z up), so
// gravity fixes roll and pitch, and the fit is a rotation about z and a
// translation, weighted least squares over the ties' points. It is refused
// when the points cannot fix the heading (fewer than two, or spanning less
// than min_spread_m horizontally).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"
#include "rvlio/refine/control_options.h"
#include "rvlio/refine/states.h"

namespace ceres {
class LossFunction;
class Problem;
}

namespace rvlio {

struct PositionTie {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_imu_point = Eigen::Vector3d::Zero();  // the point in the IMU frame, m
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();      // its measured position, m
  Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Identity();  // 1/m
  TieKernel kernel = TieKernel::kNone;
  double kernel_sigmas = 3.0;
};

// Square-root information of independent axes with one sigma (m, > 0).
Eigen::Matrix3d IsotropicSqrtInformation(double sigma_m);
// Of a covariance (m^2, symmetric positive definite): the upper Cholesky
// factor of its inverse. False when it is not positive definite.
bool SqrtInformationOf(const Eigen::Matrix3d& covariance, Eigen::Matrix3d* sqrt_information);

// The weight of iteratively reweighted least squares for a kernel at a
// whitened residual norm s (sigmas): huber min(1, c / s), cauchy
// 1 / (1 + s^2 / c^2), none 1 (c = kernel_sigmas).
double TieKernelWeight(TieKernel kernel, double kernel_sigmas, double s);
// A new ceres loss for the tie's kernel (null for none; the problem owns it).
ceres::LossFunction* MakeTieLoss(const PositionTie& tie);

// Where a time falls among the states (sorted by t_ns): between states k and
// k + 1 at alpha (two_states), or on state k alone.
struct TieAttachment {
  int k = -1;  // -1: outside the states' span
  double alpha = 0.0;
  bool two_states = false;
};
TieAttachment AttachTie(const std::vector<RefineState>& states, TimeNs t_ns);

struct ScanRange;
// A span of time, both ends included (ns).
struct TimeInterval {
  TimeNs begin_ns = 0, end_ns = 0;
};
// What the survey adds to a refinement: the ties (control points, fixes) and
// the rests of the stop-and-go marks.
struct SurveyFactors {
  std::vector<PositionTie> ties;
  std::vector<TimeInterval> rests;
  double rest_sigma_v = 0.001;  // m/s; 0: no zero-velocity factors
};
// A ZeroVelocityFactor (factors/position_factor.h) on every state of `range`
// inside one of the rests. Returns how many.
int AddRefineRestFactors(const std::vector<TimeInterval>& rests, double sigma_v,
                         const ScanRange& range, std::vector<RefineState>* states,
                         ceres::Problem* problem);
// The ties whose state(s) lie in [range.begin, range.end) as PositionFactors
// on those states' pose blocks (already in the problem). Returns how many.
int AddRefinePositionTies(const std::vector<PositionTie>& ties, const ScanRange& range,
                          std::vector<RefineState>* states, ceres::Problem* problem);
// True when a tie's state(s) lie in the range.
bool RangeHoldsTie(const std::vector<PositionTie>& ties, const ScanRange& range,
                   const std::vector<RefineState>& states);

// The tie's point in the world, carried by a trajectory (T_world_imu
// interpolated at t_ns). False outside the trajectory's span.
bool TiePointOnTrajectory(const Trajectory& trajectory, TimeNs t_ns,
                          const Eigen::Vector3d& p_imu_point, Eigen::Vector3d* p_world);

// Rotation about z and translation from the frame of p_frame into the survey
// frame of p_survey, weighted least squares (closed form). With
// tilt_sigma_rad > 0, roll and pitch are then refined too (Gauss-Newton from
// that fit): gravity fixes them only to within the accelerometer bias's
// share of it (a static alignment reads a horizontal bias b as a tilt of
// |b| / g: 0.04 m/s^2 gives 0.23 deg, 12 cm of height over 30 m), so they
// are estimated with a prior of tilt_sigma_rad at gravity's; along
// directions the points do not fix (the roll about a line of marks) the
// prior keeps gravity's.
struct AlignmentPoint {
  Eigen::Vector3d p_frame = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_survey = Eigen::Vector3d::Zero();
  double weight = 1.0;  // > 0
};
struct YawTranslation {
  Pose3 T_survey_frame;  // R = Rz(yaw) Exp((tilt_x, tilt_y, 0))
  double yaw_deg = 0.0;
  double tilt_deg[2] = {0.0, 0.0};  // the roll/pitch correction (about the frame's x and y)
  double spread_m = 0.0;  // the points' horizontal extent (survey frame)
};
// InvalidInput ("... points span X m horizontally ...") with fewer than two
// points or a horizontal extent below min_spread_m.
StatusOr<YawTranslation> FitYawTranslation(const std::vector<AlignmentPoint>& points,
                                           double min_spread_m, double tilt_sigma_rad = 0.0);
// The largest horizontal distance between two of the points (m; exact for
// points along a line, within a factor 2 otherwise: two passes).
double HorizontalSpread(const std::vector<Eigen::Vector3d>& p);

// Wall targets: the scans that saw a point of the map (at their --init pose).
struct TargetSighting {
  TimeNs t_ns = 0;  // the scan's end
  double distance_m = 0.0;  // of its nearest point to the target
  Eigen::Vector3d p_imu_point = Eigen::Vector3d::Zero();  // the target in that scan's IMU frame
};
// Keeps, per target, the max_scans scans whose nearest point lies closest
// (within radius_m) to it. Scans in any order; points in the LiDAR frame
// (each taken at the scan-end pose: the map of the --init run is made so).
class TargetSightings {
 public:
  TargetSightings(std::vector<Eigen::Vector3d> targets_world, double radius_m, int max_scans);
  // T_world_imu: the scan's --init pose at its end.
  void AddScan(const Scan& scan, const Pose3& T_world_imu, const Pose3& T_imu_lidar);
  // Per target, closest first.
  const std::vector<std::vector<TargetSighting>>& sightings() const { return sightings_; }
  bool empty() const { return targets_.empty(); }

 private:
  std::vector<Eigen::Vector3d> targets_;
  double radius_m_;
  int max_scans_;
  std::vector<std::vector<TargetSighting>> sightings_;
};

}  // namespace rvlio
