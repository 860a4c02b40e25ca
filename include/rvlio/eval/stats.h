#pragma once
// Summary statistics of an error sequence, as evo reports them.
#include <cstddef>
#include <vector>

namespace rvlio {

struct ErrorStats {
  size_t count = 0;
  double rmse = 0.0;  // sqrt(mean(e^2))
  double mean = 0.0;
  double median = 0.0;  // mean of the two middle values for an even count (numpy)
  double p95 = 0.0;     // 95th percentile, linear interpolation (numpy.percentile)
  double std = 0.0;     // population standard deviation (ddof = 0)
  double min = 0.0;
  double max = 0.0;
};

// Statistics of `errors`; all fields are 0 for an empty sequence.
ErrorStats ComputeStats(const std::vector<double>& errors);

}  // namespace rvlio
