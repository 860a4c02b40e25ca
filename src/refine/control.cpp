// Survey ties (refine/control.h): kernels, attachment to the states, the
// yaw-and-translation alignment, wall-target sightings.
#include "rvlio/refine/control.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <ceres/loss_function.h>
#include <ceres/problem.h>

#include "rvlio/common/check.h"
#include "rvlio/common/text.h"
#include "rvlio/factors/position_factor.h"
#include "rvlio/math/pose_interpolation.h"
#include "rvlio/math/so3.h"
#include "rvlio/refine/chunks.h"

namespace rvlio {

Eigen::Matrix3d IsotropicSqrtInformation(double sigma_m) {
  RVLIO_CHECK(sigma_m > 0.0);
  return Eigen::Matrix3d::Identity() / sigma_m;
}

bool SqrtInformationOf(const Eigen::Matrix3d& covariance, Eigen::Matrix3d* sqrt_information) {
  if (!covariance.allFinite()) return false;
  const Eigen::Matrix3d sym = 0.5 * (covariance + covariance.transpose());
  Eigen::LLT<Eigen::Matrix3d> llt(sym);
  if (llt.info() != Eigen::Success) return false;
  // Sigma = L L^T, Sigma^-1 = L^-T L^-1: W = L^-1 whitens (W Sigma W^T = I).
  const Eigen::Matrix3d L = llt.matrixL();
  *sqrt_information = L.inverse();
  return sqrt_information->allFinite();
}

double TieKernelWeight(TieKernel kernel, double kernel_sigmas, double s) {
  const double c = kernel_sigmas;
  switch (kernel) {
    case TieKernel::kHuber:
      return s <= c ? 1.0 : c / s;
    case TieKernel::kCauchy:
      return 1.0 / (1.0 + (s * s) / (c * c));
    case TieKernel::kNone:
      break;
  }
  return 1.0;
}

ceres::LossFunction* MakeTieLoss(const PositionTie& tie) {
  switch (tie.kernel) {
    case TieKernel::kHuber:
      return new ceres::HuberLoss(tie.kernel_sigmas);
    case TieKernel::kCauchy:
      return new ceres::CauchyLoss(tie.kernel_sigmas);
    case TieKernel::kNone:
      break;
  }
  return nullptr;
}

TieAttachment AttachTie(const std::vector<RefineState>& states, TimeNs t_ns) {
  TieAttachment a;
  if (states.empty() || t_ns < states.front().t_ns || t_ns > states.back().t_ns) return a;
  const auto it = std::lower_bound(states.begin(), states.end(), t_ns,
                                   [](const RefineState& s, TimeNs t) { return s.t_ns < t; });
  const int upper = static_cast<int>(it - states.begin());
  if (states[upper].t_ns == t_ns) {
    a.k = upper;
    return a;
  }
  a.k = upper - 1;
  a.alpha = static_cast<double>(t_ns - states[a.k].t_ns) /
            static_cast<double>(states[upper].t_ns - states[a.k].t_ns);
  a.two_states = true;
  return a;
}

namespace {
bool InRange(const TieAttachment& a, const ScanRange& range) {
  return a.k >= range.begin && a.k + (a.two_states ? 1 : 0) < range.end;
}
}  // namespace

int AddRefinePositionTies(const std::vector<PositionTie>& ties, const ScanRange& range,
                          std::vector<RefineState>* states, ceres::Problem* problem) {
  int added = 0;
  for (const PositionTie& tie : ties) {
    const TieAttachment a = AttachTie(*states, tie.t_ns);
    if (a.k < 0 || !InRange(a, range)) continue;
    double* pose_a = (*states)[a.k].pose.data();
    if (a.two_states)
      problem->AddResidualBlock(
          new PositionFactor(tie.p_imu_point, tie.p_world, tie.sqrt_information, a.alpha),
          MakeTieLoss(tie), pose_a, (*states)[a.k + 1].pose.data());
    else
      problem->AddResidualBlock(
          new PositionFactor(tie.p_imu_point, tie.p_world, tie.sqrt_information),
          MakeTieLoss(tie), pose_a);
    ++added;
  }
  return added;
}

int AddRefineRestFactors(const std::vector<TimeInterval>& rests, double sigma_v,
                         const ScanRange& range, std::vector<RefineState>* states,
                         ceres::Problem* problem) {
  int added = 0;
  for (int k = range.begin; k < range.end; ++k) {
    const TimeNs t = (*states)[k].t_ns;
    for (const TimeInterval& rest : rests) {
      if (t < rest.begin_ns || t > rest.end_ns) continue;
      problem->AddResidualBlock(new ZeroVelocityFactor(sigma_v), nullptr,
                                (*states)[k].speed_bias.data());
      ++added;
      break;
    }
  }
  return added;
}

bool RangeHoldsTie(const std::vector<PositionTie>& ties, const ScanRange& range,
                   const std::vector<RefineState>& states) {
  for (const PositionTie& tie : ties)
    if (InRange(AttachTie(states, tie.t_ns), range)) return true;
  return false;
}

bool TiePointOnTrajectory(const Trajectory& trajectory, TimeNs t_ns,
                          const Eigen::Vector3d& p_imu_point, Eigen::Vector3d* p_world) {
  Pose3 T_world_imu;
  if (trajectory.empty() || !InterpolatePose(trajectory, t_ns, &T_world_imu)) return false;
  *p_world = T_world_imu * p_imu_point;
  return true;
}

double HorizontalSpread(const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 2) return 0.0;
  auto farthest = [&p](const Eigen::Vector3d& from) {
    size_t best = 0;
    double d_best = -1.0;
    for (size_t i = 0; i < p.size(); ++i) {
      const double d = (p[i] - from).head<2>().norm();
      if (d > d_best) d_best = d, best = i;
    }
    return best;
  };
  const size_t a = farthest(p.front());
  const size_t b = farthest(p[a]);
  return (p[b] - p[a]).head<2>().norm();
}

// Weighted centroids c_f, c_s; the yaw maximizing sum w (R d_f) . d_s over
// the horizontal parts d of the centred points is atan2(sum w d_f x d_s,
// sum w d_f . d_s); t = c_s - R c_f (z included: the height offset).
namespace {

// R = Rz(yaw) Exp((a, b, 0)).
Eigen::Matrix3d YawTilt(double yaw, double a, double b) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
         so3::Exp(Eigen::Vector3d(a, b, 0.0));
}

// Weighted residuals of the centred points under x = (yaw, a, b) with t =
// c_s - R c_f, and the tilt prior (a, b) / sigma.
Eigen::VectorXd AlignmentResiduals(const std::vector<AlignmentPoint>& points,
                                   const Eigen::Vector3d& c_f, const Eigen::Vector3d& c_s,
                                   const Eigen::Vector3d& x, double tilt_sigma_rad) {
  const Eigen::Matrix3d R = YawTilt(x[0], x[1], x[2]);
  Eigen::VectorXd r(3 * points.size() + 2);
  for (size_t i = 0; i < points.size(); ++i)
    r.segment<3>(3 * i) = std::sqrt(points[i].weight) *
                          (R * (points[i].p_frame - c_f) - (points[i].p_survey - c_s));
  r.tail<2>() = x.tail<2>() / tilt_sigma_rad;
  return r;
}

// Gauss-Newton over (yaw, a, b) from the yaw-only fit (numeric Jacobian:
// three parameters); the translation follows from the centroids.
Eigen::Vector3d RefineTilt(const std::vector<AlignmentPoint>& points, const Eigen::Vector3d& c_f,
                           const Eigen::Vector3d& c_s, double yaw, double tilt_sigma_rad) {
  Eigen::Vector3d x(yaw, 0.0, 0.0);
  constexpr double kH = 1e-7;
  for (int it = 0; it < 10; ++it) {
    const Eigen::VectorXd r = AlignmentResiduals(points, c_f, c_s, x, tilt_sigma_rad);
    Eigen::MatrixXd J(r.size(), 3);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d xp = x, xm = x;
      xp[k] += kH;
      xm[k] -= kH;
      J.col(k) = (AlignmentResiduals(points, c_f, c_s, xp, tilt_sigma_rad) -
                  AlignmentResiduals(points, c_f, c_s, xm, tilt_sigma_rad)) /
                 (2 * kH);
    }
    const Eigen::Vector3d dx = (J.transpose() * J).ldlt().solve(-J.transpose() * r);
    x += dx;
    if (dx.norm() < 1e-12) break;
  }
  return x;
}

}  // namespace

StatusOr<YawTranslation> FitYawTranslation(const std::vector<AlignmentPoint>& points,
                                           double min_spread_m, double tilt_sigma_rad) {
  std::vector<Eigen::Vector3d> p_survey;
  for (const AlignmentPoint& q : points) p_survey.push_back(q.p_survey);
  YawTranslation fit;
  fit.spread_m = HorizontalSpread(p_survey);
  if (points.size() < 2 || fit.spread_m < min_spread_m)
    return Status::InvalidInput(
        std::to_string(points.size()) + " point(s) spanning " + FormatFixed(fit.spread_m, 3) +
        " m horizontally cannot fix the heading (at least 2 points " +
        FormatFixed(min_spread_m, 3) + " m apart: control.min_spread_m)");
  double w_sum = 0.0;
  Eigen::Vector3d c_f = Eigen::Vector3d::Zero(), c_s = Eigen::Vector3d::Zero();
  for (const AlignmentPoint& q : points) {
    RVLIO_CHECK(q.weight > 0.0);
    w_sum += q.weight;
    c_f += q.weight * q.p_frame;
    c_s += q.weight * q.p_survey;
  }
  c_f /= w_sum;
  c_s /= w_sum;
  double dot = 0.0, cross = 0.0;
  for (const AlignmentPoint& q : points) {
    const Eigen::Vector2d f = (q.p_frame - c_f).head<2>(), s = (q.p_survey - c_s).head<2>();
    dot += q.weight * f.dot(s);
    cross += q.weight * (f.x() * s.y() - f.y() * s.x());
  }
  Eigen::Vector3d x(std::atan2(cross, dot), 0.0, 0.0);
  if (tilt_sigma_rad > 0.0) x = RefineTilt(points, c_f, c_s, x[0], tilt_sigma_rad);
  const Eigen::Matrix3d R = YawTilt(x[0], x[1], x[2]);
  fit.T_survey_frame = Pose3(R, c_s - R * c_f);
  fit.yaw_deg = x[0] * 180.0 / M_PI;
  fit.tilt_deg[0] = x[1] * 180.0 / M_PI;
  fit.tilt_deg[1] = x[2] * 180.0 / M_PI;
  return fit;
}

TargetSightings::TargetSightings(std::vector<Eigen::Vector3d> targets_world, double radius_m,
                                 int max_scans)
    : targets_(std::move(targets_world)),
      radius_m_(radius_m),
      max_scans_(max_scans),
      sightings_(targets_.size()) {}

void TargetSightings::AddScan(const Scan& scan, const Pose3& T_world_imu,
                              const Pose3& T_imu_lidar) {
  const Pose3 T_world_lidar = T_world_imu * T_imu_lidar;
  const Pose3 T_lidar_world = T_world_lidar.Inverse();
  for (size_t i = 0; i < targets_.size(); ++i) {
    // The target in the LiDAR frame: one transform, then squared distances.
    const Eigen::Vector3f target_lidar = (T_lidar_world * targets_[i]).cast<float>();
    double best2 = radius_m_ * radius_m_;
    bool seen = false;
    for (const LidarPoint& p : scan.points) {
      const double d2 = (p.p_lidar - target_lidar).squaredNorm();  // LiDAR frame: small values
      if (d2 <= best2) best2 = d2, seen = true;
    }
    if (!seen) continue;
    std::vector<TargetSighting>& list = sightings_[i];
    TargetSighting s{scan.t_end_ns, std::sqrt(best2), T_world_imu.Inverse() * targets_[i]};
    const auto at = std::upper_bound(
        list.begin(), list.end(), s.distance_m,
        [](double d, const TargetSighting& other) { return d < other.distance_m; });
    list.insert(at, s);
    if (static_cast<int>(list.size()) > max_scans_) list.pop_back();
  }
}

}  // namespace rvlio
