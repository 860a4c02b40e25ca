#pragma once
// Batch refinement, step 1: state initialization (refine/refine.h,
// "Initialization"). Which scans are refined, the gravity vector and the
// gyro bias to start from, and each scan's initial state from the initial
// trajectory. The IMU-only velocity and bias solve that follows is in
// refine/problem.h (SolveVelocityAndBias).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/imu/options.h"
#include "rvlio/refine/refine.h"
#include "rvlio/refine/states.h"

namespace rvlio {

// Half width of the central differences that start the velocities.
constexpr TimeNs kRefineVelocityHalfWindowNs = 50000000;  // 50 ms

// The points of a refined scan as refinement reads them (LiDAR frame, m;
// absolute times), and their intensity and ring for the output map when
// the scan has them: 20 to 26 bytes a point instead of a LidarPoint's 32,
// the same values.
struct RefineScanPoints {
  std::vector<Eigen::Vector3f> p_lidar;
  std::vector<TimeNs> t_ns;
  std::vector<float> intensity;  // empty without Scan::has_intensity
  std::vector<uint16_t> ring;    // empty without Scan::has_ring
};

// The refined scans of an input: refined scan k is input scan kept[k]. Holds
// a pointer to the input, which must outlive it, and its own copy of the
// refined scans' points, so that the driver can free the input's
// (ReleaseInputPoints): scan(k) is then read for its times only.
struct RefineSequence {
  const RefineInput* input = nullptr;
  std::vector<int> kept;                 // input scan index per refined scan, increasing end times
  std::vector<RefineScanPoints> points;  // per refined scan

  int size() const { return static_cast<int>(kept.size()); }
  const Scan& scan(int k) const { return input->scans[kept[k]]; }
  const std::vector<ImuSample>& imu() const { return input->imu; }
};

// InvalidInput when the initial trajectory, the IMU or the scans are empty.
Status CheckRefineInput(const RefineInput& input);

// Keeps the scans with at least kRefineMinScanPoints points, ending inside
// the initial trajectory's span, covered by IMU data and with increasing end
// times; fills the scan counts of *stats. InvalidInput (with both time spans)
// when fewer than 2 scans remain. `input` passes CheckRefineInput.
// Copies the kept scans' points into RefineSequence::points.
StatusOr<RefineSequence> SelectRefineScans(const RefineInput& input, RefineStats* stats);

// Frees the points of every input scan (the sequence holds its own copy);
// the scans' times stay.
void ReleaseInputPoints(RefineInput* input);

// Gravity and the starting gyro bias (refine.h): the static alignment of the
// first imu.init_duration of samples, carried into the initial trajectory's
// world frame by its attitude there; with a moving start, (0, 0, -gravity)
// and a zero bias, with a warning.
struct RefineGravity {
  Eigen::Vector3d g_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();  // gyro bias to start from
  bool from_static = false;
  bool started_moving = false;
  std::string warning;  // non-empty for a moving start
};
RefineGravity InitRefineGravity(const std::vector<ImuSample>& imu, const Trajectory& init,
                                const ImuOptions& options);

// Per refined scan: its end stamp, the initial trajectory's pose there,
// central-difference velocity, gyro bias `bg`, zero accelerometer bias.
std::vector<RefineState> InitialRefineStates(const RefineSequence& sequence, const Trajectory& init,
                                             const Eigen::Vector3d& bg);

// A resumed refinement (RefineHooks::resume) starts from `resumed` instead:
// InvalidInput unless it holds one finite state per refined scan with the
// stamps of `initial` (InitialRefineStates of this input).
Status CheckResumedStates(const std::vector<RefineState>& resumed,
                          const std::vector<RefineState>& initial);

// The states as the Ceres solves need them: all components finite.
bool AllFinite(const RefineState& s);

}  // namespace rvlio
