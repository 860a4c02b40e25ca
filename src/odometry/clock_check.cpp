#include "rvlio/lidar/extrinsics.h"
#include "rvlio/odometry/clock_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rvlio/common/median.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr double kCoarseStepS = 0.002;
constexpr double kRefineToleranceS = 1e-5;
// The registration's prior: loose, so the point-to-plane terms decide; the
// mean is the previous relative rotation (constant rate).
constexpr double kRegistrationRotStd = 0.3;  // rad
constexpr double kRegistrationPosStd = 1.0;  // m

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

// The fit at one lag: residuals d_k = lidar_k - gyro_k(lag) - bias, bias the mean.
struct LagFit {
  double cost = 0.0;  // sum |d_k|^2
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
};

struct Interval {
  double a_s, b_s;
  Eigen::Vector3d lidar;
};

LagFit FitLag(const std::vector<Interval>& intervals, const GyroIntegral& gyro, double lag_s) {
  LagFit f;
  std::vector<Eigen::Vector3d> d(intervals.size());
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Interval& in = intervals[k];
    d[k] = in.lidar - gyro.Mean(in.a_s + lag_s, in.b_s + lag_s);
    f.bias += d[k];
  }
  f.bias /= static_cast<double>(intervals.size());
  for (const Eigen::Vector3d& dk : d) f.cost += (dk - f.bias).squaredNorm();
  return f;
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
  const TimeNs mid_ns = scan.t_start_ns + (scan.t_end_ns - scan.t_start_ns) / 2;
  std::optional<LidarRateSample> out;
  if (previous_ && mid_ns > previous_mid_ns_) {
    // The scan's LiDAR frame in the previous one's (the filter's "IMU" = LiDAR).
    FilterState x0;
    x0.R_world_imu = R_step_;
    solver_.Initialize(x0, mid_ns, ImuSample());
    const VoxelMap& map = *previous_;
    const IeskfUpdateResult u = solver_.Update([&](const FilterState& x, ConstraintList* c) {
      AssociationStats stats;
      Associate(p_lidar_, x.T_world_imu(), x.T_imu_lidar(), map, options_.constraints, c, &stats);
    });
    if (u.ok) {
      R_step_ = solver_.state().R_world_imu;
      const double dt_s = NsToSeconds(mid_ns - previous_mid_ns_);
      out = LidarRateSample{previous_mid_ns_, mid_ns, T_imu_lidar_.R * so3::Log(R_step_) / dt_s};
    }
  }
  previous_.emplace(options_.map);
  previous_->Insert(p_lidar_);
  previous_mid_ns_ = mid_ns;
  return out;
}

ClockCheckResult EstimateClockLag(const std::vector<LidarRateSample>& lidar,
                                  const std::vector<ImuSample>& imu,
                                  const ClockCheckOptions& options) {
  ClockCheckResult r;
  if (imu.size() < 2 || lidar.size() < 3) return r;
  const GyroIntegral gyro(imu);
  std::vector<Interval> intervals;
  for (const LidarRateSample& s : lidar) {
    const double a = gyro.Seconds(s.t0_ns), b = gyro.Seconds(s.t1_ns);
    if (b > a && gyro.Covers(a - options.max_lag_s, b + options.max_lag_s))
      intervals.push_back({a, b, s.rate_imu});
  }
  r.intervals = static_cast<int>(intervals.size());
  if (r.intervals < 3) return r;
  // Coarse grid, then golden section around the best grid lag.
  double best = 0.0, best_cost = std::numeric_limits<double>::infinity();
  for (double lag = -options.max_lag_s; lag <= options.max_lag_s + 1e-12; lag += kCoarseStepS) {
    const double c = FitLag(intervals, gyro, lag).cost;
    if (c < best_cost) best_cost = c, best = lag;
  }
  const double phi = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = best - kCoarseStepS, hi = best + kCoarseStepS;
  while (hi - lo > kRefineToleranceS) {
    const double m1 = hi - phi * (hi - lo), m2 = lo + phi * (hi - lo);
    if (FitLag(intervals, gyro, m1).cost < FitLag(intervals, gyro, m2).cost) hi = m2;
    else lo = m1;
  }
  r.lag_s = 0.5 * (lo + hi);
  const LagFit fit = FitLag(intervals, gyro, r.lag_s);
  r.gyro_bias = -fit.bias;
  // 1-sigma: Gauss-Newton on the lag (bias fitted: centred derivatives).
  const double h = 1e-4;
  std::vector<Eigen::Vector3d> J(intervals.size());
  Eigen::Vector3d J_mean = Eigen::Vector3d::Zero(), g_mean = Eigen::Vector3d::Zero(),
                  l_mean = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Interval& in = intervals[k];
    J[k] = (gyro.Mean(in.a_s + r.lag_s + h, in.b_s + r.lag_s + h) -
            gyro.Mean(in.a_s + r.lag_s - h, in.b_s + r.lag_s - h)) / (2 * h);
    J_mean += J[k];
    g_mean += gyro.Mean(in.a_s + r.lag_s, in.b_s + r.lag_s);
    l_mean += in.lidar;
  }
  const double n = static_cast<double>(intervals.size());
  J_mean /= n, g_mean /= n, l_mean /= n;
  double JtJ = 0.0, gyro_var = 0.0, lidar_var = 0.0;
  for (size_t k = 0; k < intervals.size(); ++k) {
    const Interval& in = intervals[k];
    JtJ += (J[k] - J_mean).squaredNorm();
    gyro_var += (gyro.Mean(in.a_s + r.lag_s, in.b_s + r.lag_s) - g_mean).squaredNorm();
    lidar_var += (in.lidar - l_mean).squaredNorm();
  }
  const double s2 = fit.cost / std::max(1.0, 3.0 * n - 4.0);
  r.std_s = JtJ > 0.0 ? std::sqrt(s2 / JtJ) : std::numeric_limits<double>::infinity();
  r.explained = lidar_var > 0.0 ? 1.0 - fit.cost / lidar_var : 0.0;
  r.rate_spread_rad_s = std::sqrt(gyro_var / n);
  r.enough_rotation =
      r.rate_spread_rad_s >= options.min_rate_spread && r.std_s <= options.max_std_s;
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
