#pragma once
// The plane factor of one scan in the sliding window, of the one kind the
// window's configuration chose (docs/design.md "Features as policies"):
//   SummaryScanFactor     PlaneSummaryFactor on the state's pose; the
//                         extrinsic and the time offset fixed
//   ExtrinsicScanFactor   PlaneExtrinsicFactor on the pose and the window's
//                         extrinsic (smoother.estimate_extrinsics)
//   TimeOffsetScanFactor  PlaneTimeOffsetFactor on the pose, the state's
//                         speed-bias block and the window's time offset
//                         (lidar.estimate_time_offset)
// A kind makes the factor of an association, names the parameter blocks it
// acts on, and gives the IMU pose the scan is associated at, so the solve,
// the marginalization and the association each ask it once. A new kind of
// scan factor is a new type; the window stays.
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>

#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// The parameter blocks a scan's factor may act on.
struct ScanFactorBlocks {
  double* pose;         // the state's PoseBlock (T_world_imu)
  double* speed_bias;   // the state's SpeedBiasBlock
  double* extrinsic;    // the window's T_imu_lidar (PoseBlock)
  double* time_offset;  // the window's offset, s (the leaving scan's in a marginalization)
};

// A state's pose and what moves it to its scan's time.
struct ScanPoseInput {
  const Pose3& T_world_imu;            // the state's pose
  const double* speed_bias;            // its SpeedBiasBlock
  const ScanTimeMotion& motion;        // held at the state's time
  double dtd_s;                        // the window's offset minus the scan's td_lin_s
};

// What a scan's factor is made from at an association.
struct ScanFactorInput {
  const ConstraintList& constraints;  // non-empty, Huber weights applied
  double sigma_m;                     // constraints.lidar_noise
  const Pose3& T_imu_lidar;           // the configured extrinsic
  const ScanTimeMotion& motion;       // held at the state's time
  double td_lin_s;                    // the offset the scan was deskewed with
  const Eigen::Vector3d& center_world;  // near the scan (conditioning only)
};

class ScanFactorKind {
 public:
  virtual ~ScanFactorKind() = default;
  // The scan's factor; null when its summary overflows (not finite).
  virtual std::unique_ptr<ceres::CostFunction> Make(const ScanFactorInput& in) const = 0;
  // The factor's parameter blocks, in its order.
  virtual std::vector<double*> Blocks(const ScanFactorBlocks& b) const = 0;
  // T_world_imu at the scan's time: the state's pose, unless the kind
  // estimates the time offset.
  virtual Pose3 ScanPose(const ScanPoseInput& in) const { return in.T_world_imu; }
};

// The kind for the window's options (not both estimated: SlidingWindow checks).
std::unique_ptr<ScanFactorKind> MakeScanFactorKind(bool estimate_extrinsics,
                                                   bool estimate_time_offset);

}  // namespace rvlio
