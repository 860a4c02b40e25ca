#include "rvlio/math/extrinsic_excitation.h"

#include <algorithm>
#include <cmath>

#include "rvlio/common/check.h"

namespace rvlio {

ExtrinsicExcitation::ExtrinsicExcitation(const Vector6d& prior_std) : prior_std_(prior_std) {
  RVLIO_CHECK(prior_std.minCoeff() > 0.0);
}

void ExtrinsicExcitation::Observe(const Matrix6d& covariance) {
  for (int i = 0; i < 6; ++i) {
    const double variance = covariance(i, i);
    if (!std::isfinite(variance)) continue;
    std_ratio_(i) = std::sqrt(std::max(variance, 0.0)) / prior_std_(i);
    if (std_ratio_(i) < kExcitedStdRatio) excited_[i] = true;
  }
}

void ExtrinsicExcitation::CountScan() {
  ++scans_;
  free_axis_scans_ += std::count(excited_.begin(), excited_.end(), true);
}

bool ExtrinsicExcitation::any_excited() const {
  return std::find(excited_.begin(), excited_.end(), true) != excited_.end();
}

double ExtrinsicExcitation::excited_fraction() const {
  return scans_ > 0 ? static_cast<double>(free_axis_scans_) / (6.0 * static_cast<double>(scans_))
                    : 0.0;
}

}  // namespace rvlio
