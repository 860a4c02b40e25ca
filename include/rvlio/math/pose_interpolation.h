#pragma once
// Poses between the stamped poses of a trajectory: positions linear,
// rotations slerped. The one interpolation of a trajectory (a reference
// map's initial poses, refine's initial states, chunk blending).
#include "rvlio/common/time.h"
#include "rvlio/common/types.h"
#include "rvlio/math/pose.h"

namespace rvlio {

// The pose a fraction w in [0, 1] of the way from a to b (stamp: a's):
// p = (1 - w) p_a + w p_b, q = slerp(w) of the normalized q_a, q_b.
StampedPose InterpolateBetween(const StampedPose& a, const StampedPose& b, double w);

// The pose of `trajectory` (sorted by time, non-empty) at t_ns, between the
// two poses around it. False when t_ns is outside [front, back].
bool InterpolatePose(const Trajectory& trajectory, TimeNs t_ns, Pose3* T_world_imu);

}  // namespace rvlio
