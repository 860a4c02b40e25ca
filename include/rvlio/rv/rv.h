#pragma once
// The RV pass of one scan (one filter iteration): Alg. 1 criterion ->
// Alg. 2 reinforcement -> Alg. 3 repair, applied in place to the constraint
// list before the estimator uses it (docs/design.md, "The shared measurement model" and "The RV pass").
#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"
#include "rvlio/rv/criterion.h"
#include "rvlio/rv/options.h"

namespace rvlio {

struct RvReport {
  bool active = false;                                 // criterion fired (and rv.enabled)
  Eigen::Vector3d n_alpha = Eigen::Vector3d::UnitZ();  // final plane alpha normal
  int num_constraints = 0;                             // list size (usable or not)
  int num_usable = 0;                                  // finite, non-zero normals
  int num_scv = 0;                                     // special constraint vectors (final set)
  int num_coplanar = 0;                                // usable, not SCV
  int num_reinforced = 0;  // SCVs whose weight was scaled (0 if reinforce is off)
  int num_repaired = 0;
  double K = 0.0;                  // Eq. (19) after the clamp (computed when active; applied
                                   // to the SCV weights only with rv.reinforce); 0 if inactive
  int iterations = 0;              // Alg. 2 refits
  double coplanar_fraction = 0.0;  // Alg. 1 fraction of d_i <= eps0
  // Eigenvalues of S = sum u_i u_i^T over all usable normals (Alg. 1),
  // ascending; s_eigenvalues[0] is the smallest.
  Eigen::Vector3d s_eigenvalues = Eigen::Vector3d::Zero();
  // Smallest eigenvalue of PositionInformation() of the list AFTER the edits,
  // with sigma = 1: divide by sigma^2 (m^2) for the estimator's information.
  double localizability = 0.0;
};

// Position block of the point-to-plane information matrix,
// sum_i w_i u_i u_i^T / sigma^2 (the rows of Eq. 13 weighted by R_i^-1 with
// R_i = sigma^2 / w_i). Non-finite records are skipped.
Eigen::Matrix3d PositionInformation(const ConstraintList& constraints, double sigma = 1.0);

// Smallest eigenvalue of a symmetric 3x3 matrix.
double SmallestEigenvalue(const Eigen::Matrix3d& symmetric);

// Runs the RV pass in place. T_world_lidar is the LiDAR pose the list was
// associated at (used to recompute repaired residuals). Disabled or inactive:
// the list is untouched (the report still carries the diagnostics).
// When active, the Alg. 2 plane refit always runs (it identifies the SCV set
// and plane alpha that the repair also uses, as in Alg. 3 step 2); rv.reinforce
// only switches the weight change and rv.repair the normal repair. The list is
// expected to be freshly associated: calling twice compounds the weights.
// The list never changes size; with finite input every output is finite.
RvReport ApplyRv(const RvOptions& options, const Pose3& T_world_lidar, ConstraintList* constraints,
                 RvWorkspace* workspace);
RvReport ApplyRv(const RvOptions& options, const Pose3& T_world_lidar, ConstraintList* constraints);

}  // namespace rvlio
