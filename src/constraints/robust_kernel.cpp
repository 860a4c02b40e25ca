#include "rvlio/constraints/robust_kernel.h"

#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio {

void ApplyHuberWeights(double delta_m, ConstraintList* constraints) {
  RVLIO_CHECK(delta_m > 0.0 && constraints != nullptr);
  for (Constraint& c : *constraints) {
    const double r = std::abs(c.residual);
    if (r > delta_m) c.weight *= delta_m / r;
  }
}

}  // namespace rvlio
