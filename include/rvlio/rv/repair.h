#pragma once
// Repaired vector module (paper Section 3.4, Alg. 3 steps 3-6, Eq. 20).
//
// Eq. (20) as printed, u' = (u . n_alpha) n_alpha, is the component of u
// ALONG n_alpha (out of plane alpha); it contradicts the text ("pull the
// deviated vector back toward the correct direction": wall normals are
// coplanar). We implement the in-plane projection instead (docs/design.md
// "The RV pass"):  u' = normalize(u - (u . n_alpha) n_alpha).
#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"
#include "rvlio/rv/criterion.h"
#include "rvlio/rv/options.h"

namespace rvlio {

// u' = normalize(u - (u . n_alpha) n_alpha) for unit n_alpha. Returns false
// (and leaves *u_repaired alone) when u is (numerically) parallel to n_alpha,
// where the projection has no direction.
bool ProjectIntoPlane(const Eigen::Vector3d& u, const Eigen::Vector3d& n_alpha,
                      Eigen::Vector3d* u_repaired);

// Alg. 3 steps 3-6: every coplanar (non-SCV) constraint with d_i <= eps1 gets
// the repaired normal u' and its residual recomputed at the given pose,
// r = u'^T (T_world_lidar p_lidar - q_world) (paper Eq. 3); role kRepaired.
// ws->d must hold the distances to n_alpha. Returns the number repaired.
int RepairCoplanar(const RvOptions& options, const Pose3& T_world_lidar,
                   const Eigen::Vector3d& n_alpha, const RvWorkspace& ws,
                   ConstraintList* constraints);

}  // namespace rvlio
