#include "rvlio/imu/rest.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace rvlio {
namespace {

// Prefix sums of the six signals and their squares: the variance over any
// window in O(1).
class WindowStats {
 public:
  explicit WindowStats(const std::vector<ImuSample>& imu) : sum_(imu.size() + 1), sq_(imu.size() + 1) {
    sum_[0].fill(0.0);
    sq_[0].fill(0.0);
    for (size_t i = 0; i < imu.size(); ++i) {
      for (int a = 0; a < 3; ++a) {
        const double g = imu[i].gyro_imu[a], f = imu[i].acc_imu[a];
        sum_[i + 1][a] = sum_[i][a] + g;
        sum_[i + 1][3 + a] = sum_[i][3 + a] + f;
        sq_[i + 1][a] = sq_[i][a] + g * g;
        sq_[i + 1][3 + a] = sq_[i][3 + a] + f * f;
      }
    }
  }

  // Standard deviations (root of the summed per-axis variances) of the gyro
  // and the accelerometer over samples [b, e).
  void Std(size_t b, size_t e, double* gyro, double* accel) const {
    const double n = static_cast<double>(e - b);
    double var[2] = {0.0, 0.0};
    for (int c = 0; c < 6; ++c) {
      const double mean = (sum_[e][c] - sum_[b][c]) / n;
      var[c / 3] += std::max(0.0, (sq_[e][c] - sq_[b][c]) / n - mean * mean);
    }
    *gyro = std::sqrt(var[0]);
    *accel = std::sqrt(var[1]);
  }

 private:
  std::vector<std::array<double, 6>> sum_, sq_;
};

std::vector<bool> StillSamples(const std::vector<ImuSample>& imu,
                               const RestDetectorOptions& options) {
  const WindowStats stats(imu);
  const TimeNs half_ns = SecondsToNs(0.5 * options.window_s);
  std::vector<bool> still(imu.size(), false);
  size_t b = 0, e = 0;
  for (size_t i = 0; i < imu.size(); ++i) {
    while (imu[b].t_ns < imu[i].t_ns - half_ns) ++b;
    while (e < imu.size() && imu[e].t_ns <= imu[i].t_ns + half_ns) ++e;
    if (e - b < 3) continue;
    double gyro = 0.0, accel = 0.0;
    stats.Std(b, e, &gyro, &accel);
    still[i] = gyro < options.gyro_std && accel < options.accel_std;
  }
  return still;
}

}  // namespace

std::vector<RestPeriod> FindRestPeriods(const std::vector<ImuSample>& imu,
                                        const RestDetectorOptions& options) {
  std::vector<RestPeriod> out;
  const std::vector<bool> still = StillSamples(imu, options);
  const TimeNs max_gap_ns = SecondsToNs(kRestMaxGapS);
  size_t i = 0;
  while (i < imu.size()) {
    if (!still[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j + 1 < imu.size() && still[j + 1] && imu[j + 1].t_ns - imu[j].t_ns <= max_gap_ns) ++j;
    const RestPeriod rest{imu[i].t_ns, imu[j].t_ns};
    if (rest.DurationS() >= options.min_duration_s) out.push_back(rest);
    i = j + 1;
  }
  return out;
}

}  // namespace rvlio
