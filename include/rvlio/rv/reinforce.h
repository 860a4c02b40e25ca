#pragma once
// Reinforced vector module (paper Section 3.3, Alg. 2, Eq. 19).
#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/rv/criterion.h"
#include "rvlio/rv/options.h"

namespace rvlio {

struct RefitResult {
  PlaneFit fit;        // final plane alpha (fitted on the coplanar vectors only)
  int iterations = 0;  // number of refits performed (0: Alg. 1 found no SCV)
  int num_scv = 0;
  int num_coplanar = 0;
  bool converged = true;  // false when max_iterations stopped the loop early
};

// Alg. 2 steps 3-9: starting from the Alg. 1 plane and classes in ws, repeat
// { drop the current SCVs from S, refit n_alpha on the remaining vectors,
// recompute d_i for all, mark remaining vectors with d_i > eps0 as new SCVs }
// until no remaining vector has d_i > eps0 or max_iterations refits were done.
// SCVs are cumulative (a dropped row is never added back, as in the paper's
// "delete rows in A"); S is updated incrementally by subtracting u u^T of the
// dropped rows. On return ws->d holds the distances to the final plane.
// S_all is the scatter of all usable vectors (CriterionResult::S).
RefitResult RefitPlane(const RvOptions& options, const Eigen::Matrix3d& S_all,
                       const PlaneFit& initial, RvWorkspace* ws);

// Eq. (19): K = k0 * |SCVs| / |coplanar|. With no coplanar vector the ratio is
// undefined and K = 1 (SCVs left as they are). With options.clamp,
// K = min(K, 1) so that the SCV noise K R never exceeds R.
double ReinforcementCoefficient(const RvOptions& options, int num_scv, int num_coplanar);

// Alg. 2 step 11: the SCV rows' noise becomes K R, i.e. their information
// multiplier `weight` is divided by K; their role becomes kScv. Returns the
// number of constraints reinforced. Requires K > 0 and finite. With
// max_abs_residual_m > 0 (ours, rv.reinforce_max_residual), an SCV whose
// point-to-plane residual at the current iterate exceeds it keeps its plain
// weight (its role is still kScv): a mis-associated feature is not amplified.
int ReinforceScv(double K, const RvWorkspace& ws, ConstraintList* constraints,
                 double max_abs_residual_m = 0.0);

}  // namespace rvlio
