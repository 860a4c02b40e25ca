#include "rvlio/odometry/clock_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "rvlio/common/median.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr double kCoarseStepS = 0.002;
constexpr double kRefineToleranceS = 1e-5;
// The registration's prior: loose, so the point-to-plane terms decide; the
// mean is the previous relative rotation (constant rate).
constexpr double kRegistrationRotStd = 0.3;  // rad
constexpr double kRegistrationPosStd = 1.0;  // m
// Shares of the sweep (by point time) whose weights a rotation sample keeps.
constexpr int kTimeParts = 10;

using Matrix6d = Eigen::Matrix<double, 6, 6>;

IeskfOptions RegistrationOptions(const IeskfOptions& o) {
  IeskfOptions r = o;
  r.estimate_extrinsics = false;
  r.init_rot_std = kRegistrationRotStd;
  r.init_pos_std = kRegistrationPosStd;
  return r;
}

RvOptions WithoutRv(RvOptions rv) {
  rv.enabled = false;
  return rv;
}

// Cumulative integral of the gyro rate (trapezoid) at the IMU sample times,
// so that the mean rate over any interval is two interpolations.
class GyroIntegral {
 public:
  explicit GyroIntegral(const std::vector<ImuSample>& imu) : t0_ns_(imu.front().t_ns) {
    t_s_.reserve(imu.size());
    c_.reserve(imu.size());
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < imu.size(); ++i) {
      if (i > 0)
        c += 0.5 * (imu[i].gyro_imu + imu[i - 1].gyro_imu) * NsToSeconds(imu[i].t_ns - imu[i - 1].t_ns);
      t_s_.push_back(NsToSeconds(imu[i].t_ns - t0_ns_));
      c_.push_back(c);
    }
  }
  double Seconds(TimeNs t_ns) const { return NsToSeconds(t_ns - t0_ns_); }
  bool Covers(double a_s, double b_s) const { return a_s >= t_s_.front() && b_s <= t_s_.back(); }
  // Mean rate over [a_s, b_s] (seconds from the first sample, covered).
  Eigen::Vector3d Mean(double a_s, double b_s) const { return (At(b_s) - At(a_s)) / (b_s - a_s); }

 private:
  Eigen::Vector3d At(double t_s) const {
    const auto it = std::upper_bound(t_s_.begin(), t_s_.end(), t_s);
    const size_t i = std::min<size_t>(std::max<ptrdiff_t>(it - t_s_.begin(), 1), t_s_.size() - 1);
    const double span = t_s_[i] - t_s_[i - 1];
    const double w = span > 0.0 ? (t_s - t_s_[i - 1]) / span : 0.0;
    return c_[i - 1] + w * (c_[i] - c_[i - 1]);
  }
  TimeNs t0_ns_;
  std::vector<double> t_s_;
  std::vector<Eigen::Vector3d> c_;
};

// A rotation sample in seconds from the first IMU sample.
struct Interval {
  struct Part {
    double a_s, b_s;
    Eigen::Matrix3d weight;
  };
  Eigen::Vector3d lidar;
  double period_s;
  std::vector<Part> parts;
  double first_s, last_s;  // the span of the parts
};

// The gyro's prediction of a LiDAR rotation sample at a lag.
Eigen::Vector3d Predicted(const Interval& in, const GyroIntegral& gyro, double lag_s) {
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (const Interval::Part& p : in.parts) g += p.weight * gyro.Mean(p.a_s + lag_s, p.b_s + lag_s);
  return g;
}

// The fit at one lag: residuals d_k = lidar_k - gyro_k(lag) - bias, bias the mean.
struct LagFit {
  double cost = 0.0;  // sum |d_k|^2
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
};

LagFit FitLag(const std::vector<Interval>& intervals, const GyroIntegral& gyro, double lag_s) {
  LagFit f;
  std::vector<Eigen::Vector3d> d(intervals.size());
  for (size_t k = 0; k < intervals.size(); ++k) {
    d[k] = intervals[k].lidar - Predicted(intervals[k], gyro, lag_s);
    f.bias += d[k];
  }
  f.bias /= static_cast<double>(intervals.size());
  for (const Eigen::Vector3d& dk : d) f.cost += (dk - f.bias).squaredNorm();
  return f;
}

// A point's key in a scan's point-time table: its coordinates' bits (the
// map returns a stored point's float coordinates unchanged).
uint64_t PointKey(const Eigen::Vector3f& p) {
  uint32_t b[3];
  std::memcpy(b, p.data(), sizeof(b));
  return (uint64_t{b[0]} * 0x9E3779B97F4A7C15ull) ^ (uint64_t{b[1]} * 0xC2B2AE3D27D4EB4Full) ^
         (uint64_t{b[2]} * 0x165667B19E3779F9ull);
}

std::vector<double> PeriodsS(const std::vector<TimeNs>& t_ns) {
  std::vector<double> p;
  for (size_t i = 1; i < t_ns.size(); ++i) p.push_back(NsToSeconds(t_ns[i] - t_ns[i - 1]));
  return p;
}

}  // namespace

ScanRotationTracker::ScanRotationTracker(const OdometryOptions& options)
    : options_(options),
      preprocessor_(options.lidar),
      solver_(RegistrationOptions(options.ieskf), options.imu, options.constraints,
              WithoutRv(options.rv)),
      T_imu_lidar_(ImuTLidar(options.extrinsics)) {}

std::optional<LidarRateSample> ScanRotationTracker::Add(const Scan& scan) {
  preprocessor_.Downsample(scan, &downsampled_);
  if (static_cast<int>(downsampled_.points.size()) < kMinScanPoints) {
    previous_.reset();
    return std::nullopt;
  }
  p_lidar_.resize(downsampled_.points.size());
  for (size_t i = 0; i < p_lidar_.size(); ++i)
    p_lidar_[i] = downsampled_.points[i].p_lidar.cast<double>();
  std::optional<LidarRateSample> out;
  if (previous_ && scan.t_start_ns > previous_start_ns_) {
    // The scan's LiDAR frame in the previous one's (the filter's "IMU" = LiDAR),
    // predicted by the previous step (constant motion).
    FilterState x0;
    x0.R_world_imu = R_step_;
    x0.p_world_imu = t_step_;
    solver_.Initialize(x0, scan.t_end_ns, ImuSample());
    const VoxelMap& map = *previous_;
    const IeskfUpdateResult u = solver_.Update([&](const FilterState& x, ConstraintList* c) {
      AssociationStats stats;
      Associate(p_lidar_, x.T_world_imu(), x.T_imu_lidar(), map, options_.constraints, c, &stats);
    });
    if (u.ok) out = Sample(x0, scan.t_start_ns - previous_start_ns_);
    if (out) {
      R_step_ = solver_.state().R_world_imu;
      t_step_ = solver_.state().p_world_imu;
    }
  }
  KeepAsPrevious(scan.t_start_ns);
  return out;
}

void ScanRotationTracker::KeepAsPrevious(TimeNs t_start_ns) {
  previous_.emplace(options_.map);
  previous_->Insert(p_lidar_);
  previous_times_.clear();
  for (const LidarPoint& p : downsampled_.points) previous_times_.emplace(PointKey(p.p_lidar), p.t_ns);
  previous_start_ns_ = t_start_ns;
}

void ScanRotationTracker::AssociateAtSolution() {
  const FilterState& x = solver_.state();
  map_time_ns_.clear();
  const auto note_times = [this](const NeighborBuffer& neighbors) {
    double sum_ns = 0.0;
    int found = 0;
    for (int j = 0; j < neighbors.size; ++j) {
      const auto it = previous_times_.find(PointKey(neighbors.points[j].cast<float>()));
      if (it == previous_times_.end()) continue;
      sum_ns += static_cast<double>(it->second - previous_start_ns_);
      ++found;
    }
    map_time_ns_.push_back(found > 0 ? previous_start_ns_ + std::llround(sum_ns / found) : -1);
  };
  AssociateWith(p_lidar_, x.T_world_imu() * x.T_imu_lidar(), *previous_, options_.constraints,
                &constraints_, nullptr, nullptr, note_times);
}

// The registration's solution is, to first order, H^-1 (sum_i H_i x_i +
// H_prior x_prior): H_i = J_i^T J_i / sigma^2 at the solution, x_i the
// relative pose point i sees (the sensor's motion from its matched points'
// time to its own) and x_prior the prediction. The constraints are binned by
// their point's time into kTimeParts shares of the sweep; a part's weight is
// the rotation rows of H^-1 H_part (its translation columns with the lever
// arm: rotating about the IMU moves the LiDAR by theta x t_imu_lidar), its
// times the rotation-information-weighted means of its points' and matched
// points' times. The prior's share is taken out of the rotation. Nothing
// when H is singular.
std::optional<LidarRateSample> ScanRotationTracker::Sample(const FilterState& prior,
                                                           TimeNs period_ns) {
  AssociateAtSolution();
  const FilterState& x = solver_.state();
  const double inv_sigma2 =
      1.0 / (options_.constraints.lidar_noise * options_.constraints.lidar_noise);
  std::array<Matrix6d, kTimeParts> H_part;
  for (Matrix6d& h : H_part) h.setZero();
  std::array<double, kTimeParts> t1_sum{}, t0_sum{}, w_sum{};  // ns from the scan start
  const TimeNs start_ns = downsampled_.t_start_ns;
  const TimeNs span_ns = std::max<TimeNs>(1, downsampled_.t_end_ns - start_ns);
  size_t i = 0;  // the constraints are in point order
  for (size_t k = 0; k < constraints_.size(); ++k) {
    const Constraint& c = constraints_[k];
    while (i < p_lidar_.size() && p_lidar_[i] != c.p_lidar) ++i;
    if (i == p_lidar_.size()) break;
    if (map_time_ns_[k] < 0) continue;
    const TimeNs t_ns = downsampled_.points[i].t_ns;
    const int b = static_cast<int>(
        std::clamp<TimeNs>((t_ns - start_ns) * kTimeParts / span_ns, 0, kTimeParts - 1));
    Eigen::Matrix<double, 1, 6> J;
    PointToPlaneResidual(c, x.T_world_imu(), x.T_imu_lidar(), &J);
    H_part[b] += c.weight * inv_sigma2 * J.transpose() * J;
    const double w = c.weight * J.head<3>().squaredNorm();
    t1_sum[b] += w * static_cast<double>(t_ns - start_ns);
    t0_sum[b] += w * static_cast<double>(map_time_ns_[k] - start_ns);
    w_sum[b] += w;
  }
  Matrix6d H_prior = Matrix6d::Zero();
  H_prior.diagonal().head<3>().setConstant(1.0 / (kRegistrationRotStd * kRegistrationRotStd));
  H_prior.diagonal().tail<3>().setConstant(1.0 / (kRegistrationPosStd * kRegistrationPosStd));
  Matrix6d H = H_prior;
  for (const Matrix6d& h : H_part) H += h;
  const Eigen::LDLT<Matrix6d> ldlt(H);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nullopt;
  Eigen::Matrix<double, 6, 1> x_prior;
  x_prior << so3::Log(prior.R_world_imu), prior.p_world_imu;
  const Eigen::Vector3d theta_lidar =
      so3::Log(x.R_world_imu) - ldlt.solve(H_prior * x_prior).head<3>();
  const Eigen::Matrix3d& R_il = T_imu_lidar_.R;
  const Eigen::Matrix3d R_li = R_il.transpose();
  const Eigen::Matrix3d t_il_hat = so3::Hat(T_imu_lidar_.t);
  LidarRateSample s;
  s.period_ns = period_ns;
  s.rate_imu = R_il * theta_lidar / NsToSeconds(period_ns);
  for (int b = 0; b < kTimeParts; ++b) {
    if (!(w_sum[b] > 0.0)) continue;
    const Matrix6d M = ldlt.solve(H_part[b]);
    RotationSamplePart p;
    p.t1_ns = start_ns + std::llround(t1_sum[b] / w_sum[b]);
    p.t0_ns = start_ns + std::llround(t0_sum[b] / w_sum[b]);
    // Per unit of the gyro's rotation over the part (IMU frame): the LiDAR
    // rotates by R_li theta and moves by R_li (theta x t_imu_lidar).
    p.weight = R_il * (M.topLeftCorner<3, 3>() * R_li - M.topRightCorner<3, 3>() * R_li * t_il_hat) /
               NsToSeconds(period_ns) * NsToSeconds(p.t1_ns - p.t0_ns);
    if (p.t1_ns > p.t0_ns) s.parts.push_back(p);
  }
  if (s.parts.empty()) return std::nullopt;
  return s;
}

namespace {

// The intervals the gyro covers with the lag's search range around them.
std::vector<Interval> CoveredIntervals(const std::vector<LidarRateSample>& lidar,
                                       const GyroIntegral& gyro, double max_lag_s) {
  std::vector<Interval> intervals;
  for (const LidarRateSample& s : lidar) {
    Interval in{s.rate_imu, NsToSeconds(s.period_ns), {}, std::numeric_limits<double>::infinity(),
                -std::numeric_limits<double>::infinity()};
    for (const RotationSamplePart& p : s.parts) {
      in.parts.push_back({gyro.Seconds(p.t0_ns), gyro.Seconds(p.t1_ns), p.weight});
      in.first_s = std::min(in.first_s, in.parts.back().a_s);
      in.last_s = std::max(in.last_s, in.parts.back().b_s);
    }
    if (!in.parts.empty() && gyro.Covers(in.first_s - max_lag_s, in.last_s + max_lag_s))
      intervals.push_back(std::move(in));
  }
  return intervals;
}

// The lag of least cost: a grid of kCoarseStepS over +-max_lag_s, then golden
// section around the best grid lag.
double BestLag(const std::vector<Interval>& intervals, const GyroIntegral& gyro, double max_lag_s) {
  double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
  for (double lag = -max_lag_s; lag <= max_lag_s + 1e-12; lag += kCoarseStepS) {
    const double c = FitLag(intervals, gyro, lag).cost;
    if (c < best_cost) best_cost = c, best = lag;
  }
  const double phi = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = std::max(best - kCoarseStepS, -max_lag_s), hi = std::min(best + kCoarseStepS, max_lag_s);
  while (hi - lo > kRefineToleranceS) {
    const double m1 = hi - phi * (hi - lo), m2 = lo + phi * (hi - lo);
    if (FitLag(intervals, gyro, m1).cost < FitLag(intervals, gyro, m2).cost) hi = m2;
    else lo = m1;
  }
  return 0.5 * (lo + hi);
}

// The 1-sigma of the lag: a sandwich estimate over the scores
// s_k = J_k . d_k (J_k = d(prediction_k)/d(lag), d_k the residual, both
// centred: the bias is fitted) with Bartlett weights over n^(1/3) lags,
// var = sum_l w_l sum_k s_k s_{k+l} / (sum_k |J_k|^2)^2. The residuals are
// mostly registration errors, several times larger about some axes than about
// others and correlated from scan to scan; the white-noise formula (one
// residual variance for every axis and sample) was up to 1.4 times too small
// on the simulated flights (docs/time_offset.md).
double LagStd(const std::vector<Eigen::Vector3d>& J, const std::vector<Eigen::Vector3d>& d) {
  const size_t n = J.size();
  double JtJ = 0.0;
  std::vector<double> score(n);
  for (size_t k = 0; k < n; ++k) {
    JtJ += J[k].squaredNorm();
    score[k] = J[k].dot(d[k]);
  }
  if (!(JtJ > 0.0)) return std::numeric_limits<double>::infinity();
  const size_t max_lag = static_cast<size_t>(std::ceil(std::cbrt(static_cast<double>(n))));
  double var = 0.0;
  for (size_t l = 0; l <= max_lag && l < n; ++l) {
    double sum = 0.0;
    for (size_t k = 0; k + l < n; ++k) sum += score[k] * score[k + l];
    var += (l == 0 ? 1.0 : 2.0 * (1.0 - static_cast<double>(l) / (max_lag + 1))) * sum;
  }
  return std::sqrt(std::max(var, 0.0)) / JtJ;
}

ClockVerdict Judge(const ClockCheckResult& r, const ClockCheckOptions& options) {
  if (r.rate_spread_rad_s < options.min_rate_spread) return ClockVerdict::kNotEnoughRotation;
  if (r.moving_s < options.min_moving_s) return ClockVerdict::kTooShort;
  if (!(r.std_s <= options.max_std_s)) return ClockVerdict::kTooUncertain;
  return ClockVerdict::kJudged;
}

}  // namespace

ClockCheckResult EstimateClockLag(const std::vector<LidarRateSample>& lidar,
                                  const std::vector<ImuSample>& imu,
                                  const ClockCheckOptions& options) {
  ClockCheckResult r;
  if (imu.size() < 2 || lidar.size() < 3) return r;
  const GyroIntegral gyro(imu);
  const std::vector<Interval> intervals = CoveredIntervals(lidar, gyro, options.max_lag_s);
  r.intervals = static_cast<int>(intervals.size());
  if (r.intervals < 3) return r;
  r.lag_s = BestLag(intervals, gyro, options.max_lag_s);
  const LagFit fit = FitLag(intervals, gyro, r.lag_s);
  r.gyro_bias = -fit.bias;
  const double n = static_cast<double>(intervals.size());
  const double h = 1e-4;  // s, for the centred derivative
  std::vector<Eigen::Vector3d> J(intervals.size()), d(intervals.size()), g(intervals.size());
  Eigen::Vector3d J_mean = Eigen::Vector3d::Zero(), g_mean = Eigen::Vector3d::Zero(),
                  l_mean = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Interval& in = intervals[k];
    J[k] = (Predicted(in, gyro, r.lag_s + h) - Predicted(in, gyro, r.lag_s - h)) / (2 * h);
    g[k] = Predicted(in, gyro, r.lag_s);
    d[k] = in.lidar - g[k] - fit.bias;
    J_mean += J[k] / n, g_mean += g[k] / n, l_mean += in.lidar / n;
  }
  double gyro_var = 0.0, lidar_var = 0.0;
  for (size_t k = 0; k < intervals.size(); ++k) {
    J[k] -= J_mean;
    gyro_var += (g[k] - g_mean).squaredNorm();
    lidar_var += (intervals[k].lidar - l_mean).squaredNorm();
    if ((g[k] - g_mean).norm() >= options.min_rate_spread)
      r.moving_s += intervals[k].period_s;
  }
  r.std_s = LagStd(J, d);
  r.explained = lidar_var > 0.0 ? 1.0 - fit.cost / lidar_var : 0.0;
  r.rate_spread_rad_s = std::sqrt(gyro_var / n);
  r.verdict = Judge(r, options);
  return r;
}

StampReport AnalyzeStamps(const std::vector<TimeNs>& scan_start_ns,
                          const std::vector<TimeNs>& scan_end_ns,
                          const std::vector<TimeNs>& imu_ns) {
  StampReport r;
  r.scans = static_cast<int>(scan_start_ns.size());
  r.imu_samples = static_cast<int>(imu_ns.size());
  const std::vector<double> scan_p = PeriodsS(scan_start_ns);
  r.scan_period_s = UpperMedian(scan_p);
  double sum_sq = 0.0;
  int regular = 0;
  for (double p : scan_p) {
    const long k = r.scan_period_s > 0.0 ? std::lround(p / r.scan_period_s) : 1;
    if (k >= 2) {
      r.dropped_scans += static_cast<int>(k - 1);
      continue;
    }
    sum_sq += (p - r.scan_period_s) * (p - r.scan_period_s);
    ++regular;
  }
  r.scan_jitter_s = regular > 0 ? std::sqrt(sum_sq / regular) : 0.0;
  std::vector<double> durations;
  for (size_t i = 0; i < scan_start_ns.size() && i < scan_end_ns.size(); ++i)
    durations.push_back(NsToSeconds(scan_end_ns[i] - scan_start_ns[i]));
  r.scan_duration_s = UpperMedian(durations);
  const std::vector<double> imu_p = PeriodsS(imu_ns);
  const double imu_period = UpperMedian(imu_p);
  r.imu_rate_hz = imu_period > 0.0 ? 1.0 / imu_period : 0.0;
  sum_sq = 0.0;
  for (double p : imu_p) {
    sum_sq += (p - imu_period) * (p - imu_period);
    if (p > 2.0 * imu_period) ++r.imu_gaps;
    r.imu_max_gap_s = std::max(r.imu_max_gap_s, p);
  }
  r.imu_jitter_s = imu_p.empty() ? 0.0 : std::sqrt(sum_sq / static_cast<double>(imu_p.size()));
  return r;
}

}  // namespace rvlio
