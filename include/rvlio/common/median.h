#pragma once
// The two medians the project uses; they differ for an even count.
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace rvlio {

// The median of a sample (numpy.median): the middle value, or the mean of the
// two middle values. NaN for no values.
inline double Median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

// The upper median: the middle value, or the upper of the two middle values,
// so always one of the values (a typical period or stamp step; robust
// thresholds that must not average two samples). T{} for no values.
template <typename T>
T UpperMedian(std::vector<T> v) {
  if (v.empty()) return T{};
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace rvlio
