#include "rvlio/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>

namespace rvlio {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

void CheckMatched(const Trajectory& ref, const Trajectory& est) {
  RVLIO_CHECK_MSG(ref.size() == est.size(), "metrics need matched trajectories");
}

// Relative motion from pose i to pose j: T_i^-1 T_j.
struct Relative {
  Eigen::Quaterniond q;
  Eigen::Vector3d t;
};

Relative Between(const StampedPose& a, const StampedPose& b) {
  const Eigen::Quaterniond qa_inv = a.q_world_imu.conjugate();
  return {qa_inv * b.q_world_imu, qa_inv * (b.p_world_imu - a.p_world_imu)};
}

std::vector<std::pair<size_t, size_t>> ConsecutivePairs(const std::vector<size_t>& ids) {
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

// evo.core.filters.filter_pairs_by_index (all_pairs = false).
std::vector<size_t> IdsByIndex(size_t n, size_t delta) {
  std::vector<size_t> ids;
  for (size_t i = 0; i < n; i += delta) ids.push_back(i);
  return ids;
}

// evo.core.filters.filter_pairs_by_path (all_pairs = false): the path is
// accumulated from pose 0 and reset at each id.
std::vector<size_t> IdsByPath(const Trajectory& est, double delta_m) {
  std::vector<size_t> ids;
  double path = 0.0;
  for (size_t i = 0; i < est.size(); ++i) {
    if (i > 0) path += (est[i].p_world_imu - est[i - 1].p_world_imu).norm();
    if (path >= delta_m) {
      ids.push_back(i);
      path = 0.0;
    }
  }
  return ids;
}

}  // namespace

double RotationAngle(const Eigen::Quaterniond& q) {
  return 2.0 * std::atan2(q.vec().norm(), std::fabs(q.w()));
}

std::vector<double> ApeTranslationErrors(const Trajectory& ref, const Trajectory& est) {
  CheckMatched(ref, est);
  std::vector<double> e(ref.size());
  for (size_t k = 0; k < ref.size(); ++k) e[k] = (ref[k].p_world_imu - est[k].p_world_imu).norm();
  return e;
}

std::vector<double> ApeRotationErrorsDeg(const Trajectory& ref, const Trajectory& est) {
  CheckMatched(ref, est);
  std::vector<double> e(ref.size());
  for (size_t k = 0; k < ref.size(); ++k)
    e[k] = kRadToDeg * RotationAngle(ref[k].q_world_imu.conjugate() * est[k].q_world_imu);
  return e;
}

std::vector<std::pair<size_t, size_t>> RpePairs(const Trajectory& est, const RpeOptions& options) {
  if (options.unit == RpeUnit::kFrames) {
    RVLIO_CHECK(options.delta >= 1.0 && std::floor(options.delta) == options.delta);
    return ConsecutivePairs(IdsByIndex(est.size(), static_cast<size_t>(options.delta)));
  }
  RVLIO_CHECK(options.delta > 0.0);
  return ConsecutivePairs(IdsByPath(est, options.delta));
}

// TUM RGB-D benchmark / evo.core.metrics.RPE.rpe_base:
//   E_i = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j).
StatusOr<RpeResult> ComputeRpe(const Trajectory& ref, const Trajectory& est,
                               const RpeOptions& options) {
  CheckMatched(ref, est);
  const std::vector<std::pair<size_t, size_t>> pairs = RpePairs(est, options);
  if (pairs.empty()) {
    std::ostringstream os;
    os << "RPE delta " << options.delta << (options.unit == RpeUnit::kFrames ? " frames" : " m")
       << " leaves no pose pair among " << est.size() << " matched poses";
    return Status::InvalidInput(os.str());
  }
  std::vector<double> trans(pairs.size()), rot(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    const Relative q_rel = Between(ref[i], ref[j]);
    const Relative p_rel = Between(est[i], est[j]);
    const Eigen::Quaterniond q_inv = q_rel.q.conjugate();
    const Eigen::Vector3d t_err = q_inv * (p_rel.t - q_rel.t);
    trans[k] = t_err.norm();
    rot[k] = kRadToDeg * RotationAngle(q_inv * p_rel.q);
  }
  RpeResult r;
  r.pairs = pairs.size();
  r.trans_m = ComputeStats(trans);
  r.rot_deg = ComputeStats(rot);
  return r;
}

double EndPointError(const Trajectory& ref, const Trajectory& est) {
  CheckMatched(ref, est);
  RVLIO_CHECK(!ref.empty());
  return (ref.back().p_world_imu - est.back().p_world_imu).norm();
}

AlongAxisError ComputeAlongAxisError(const Trajectory& ref, const Trajectory& est) {
  CheckMatched(ref, est);
  AlongAxisError out;
  if (ref.empty()) return out;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const StampedPose& p : ref) mean += p.p_world_imu;
  mean /= static_cast<double>(ref.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const StampedPose& p : ref)
    cov += (p.p_world_imu - mean) * (p.p_world_imu - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.eigenvalues()(2) > 0.0) out.axis = eig.eigenvectors().col(2).normalized();
  double sum_sq = 0.0;
  for (size_t k = 0; k < ref.size(); ++k) {
    const double a = out.axis.dot(est[k].p_world_imu - ref[k].p_world_imu);
    out.errors_m.push_back(a);
    sum_sq += a * a;
    out.max_abs_m = std::max(out.max_abs_m, std::fabs(a));
  }
  out.rmse_m = std::sqrt(sum_sq / static_cast<double>(ref.size()));
  return out;
}

}  // namespace rvlio
