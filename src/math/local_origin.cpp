#include "rvlio/math/local_origin.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace rvlio {
namespace {

// The median of at most this many points (evenly strided over the input) is
// taken: the origin is rounded to kLocalOriginGrid_m anyway, and a 10 M
// point survey is not copied.
constexpr size_t kMaxOriginSamples = 1 << 16;

// Per axis, the median of the finite positions p(0), ..., p(n - 1), rounded
// to a multiple of kLocalOriginGrid_m (zero when none is finite).
template <class Position>
LocalOrigin RoundedMedian(size_t n, Position p) {
  const size_t stride = std::max<size_t>(1, n / kMaxOriginSamples);
  std::vector<Eigen::Vector3d> samples;
  samples.reserve(n / stride + 1);
  for (size_t i = 0; i < n; i += stride)
    if (p(i).allFinite()) samples.push_back(p(i));
  LocalOrigin origin;
  if (samples.empty()) return origin;
  std::vector<double> axis(samples.size());
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < samples.size(); ++i) axis[i] = samples[i][a];
    const auto middle = axis.begin() + static_cast<std::ptrdiff_t>(axis.size() / 2);
    std::nth_element(axis.begin(), middle, axis.end());
    origin.t_user_local[a] = kLocalOriginGrid_m * std::round(*middle / kLocalOriginGrid_m) + 0.0;  // no -0
  }
  return origin;
}

}  // namespace

void LocalOrigin::ToLocal(std::vector<Eigen::Vector3d>* points) const {
  if (IsZero()) return;
  for (Eigen::Vector3d& p : *points) p -= t_user_local;
}

void LocalOrigin::ToUser(std::vector<Eigen::Vector3d>* points) const {
  if (IsZero()) return;
  for (Eigen::Vector3d& p : *points) p += t_user_local;
}

void LocalOrigin::ToLocal(Trajectory* trajectory) const {
  for (StampedPose& pose : *trajectory) pose.p_world_imu -= t_user_local;
}

void LocalOrigin::ToUser(Trajectory* trajectory) const {
  for (StampedPose& pose : *trajectory) pose.p_world_imu += t_user_local;
}

double Float32Step(double v) {
  const float f = static_cast<float>(std::abs(v));
  return static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity()) - f);
}

LocalOrigin ChooseLocalOrigin(const std::vector<Eigen::Vector3d>& p_user) {
  return RoundedMedian(p_user.size(), [&](size_t i) -> const Eigen::Vector3d& { return p_user[i]; });
}

LocalOrigin ChooseLocalOrigin(const Trajectory& trajectory) {
  return RoundedMedian(trajectory.size(), [&](size_t i) -> const Eigen::Vector3d& {
    return trajectory[i].p_world_imu;
  });
}

}  // namespace rvlio
