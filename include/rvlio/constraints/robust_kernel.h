#pragma once
// The robust kernel on point-to-plane residuals, shared by the sliding
// window (smoother.sliding_window_huber_delta) and batch refinement
// (refine.huber_delta).
//
// Iteratively reweighted Huber: the gradient of the Huber cost of a residual
// r equals that of the weighted square w r^2 / 2 with w = min(1, delta / |r|),
// evaluated at the linearization point. The weight goes into the constraint
// record (on top of the RV weight) because the plane factors sum a whole
// scan's residuals: a ceres::LossFunction would act on that scan's squared
// norm instead of on each residual.
#include "rvlio/constraints/constraint.h"

namespace rvlio {

// Multiplies each constraint's weight by min(1, delta_m / |residual|), with
// the residual field as it stands (m). delta_m > 0.
void ApplyHuberWeights(double delta_m, ConstraintList* constraints);

}  // namespace rvlio
