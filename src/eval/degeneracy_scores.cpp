#include "rvlio/eval/degeneracy_scores.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rvlio/eval/time_matching.h"
#include "rvlio/eval/evaluate.h"

namespace rvlio {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The labels' stamps as a trajectory (for the one time association).
Trajectory Stamps(const std::vector<DegeneracyLabel>& labels) {
  Trajectory t(labels.size());
  for (size_t i = 0; i < labels.size(); ++i) t[i].t_ns = labels[i].t_ns;
  return t;
}

// partner[i] = the index in `other` associated with element i of `ref` (-1: none).
StatusOr<std::vector<long>> Partners(const Trajectory& ref, const Trajectory& other,
                                     double max_dt_s) {
  StatusOr<Association> a = Associate(ref, other, max_dt_s);
  if (!a.ok()) return a.status();
  std::vector<long> partner(ref.size(), -1);
  for (size_t k = 0; k < a->size(); ++k)
    partner[a->ref_index[k]] = static_cast<long>(a->est_index[k]);
  return partner;
}

double Ratio(size_t num, size_t den) {
  return den == 0 ? kNaN : static_cast<double>(num) / static_cast<double>(den);
}

bool HasDirection(const Eigen::Vector3d& v) { return v.allFinite() && v.norm() > 1e-9; }

double Rms(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

// The error along the true weak direction (see the header).
Status AddWeakDirectionError(const std::vector<DegeneracyLabel>& truth,
                             const Trajectory& ground_truth, const Trajectory& estimate,
                             const EvalOptions& options, DegeneracyScores* s) {
  StatusOr<EvalResult> eval = Evaluate(ground_truth, estimate, options);
  if (!eval.ok()) return eval.status();
  s->warnings = eval->warnings;
  const Trajectory stamps = Stamps(truth);
  StatusOr<std::vector<long>> est_of = Partners(stamps, estimate, options.max_dt);
  if (!est_of.ok()) return est_of.status();
  StatusOr<std::vector<long>> gt_of = Partners(stamps, ground_truth, options.max_dt);
  if (!gt_of.ok()) return gt_of.status();
  std::vector<double> along, along_degenerate;
  const Eigen::Vector3d* previous = nullptr;
  for (size_t i = 0; i < truth.size(); ++i) {
    const long e = (*est_of)[i], g = (*gt_of)[i];
    if (e < 0 || g < 0) continue;
    const Eigen::Vector3d& p_gt = ground_truth[static_cast<size_t>(g)].p_world_imu;
    const Eigen::Vector3d error =
        eval->T_ref_est * estimate[static_cast<size_t>(e)].p_world_imu - p_gt;
    along.push_back(std::abs(error.dot(truth[i].weak_dir_world)));
    if (truth[i].degenerate) along_degenerate.push_back(along.back());
    if (previous) s->path_length_m += (p_gt - *previous).norm();
    previous = &p_gt;
  }
  s->error_scans = along.size();
  if (along.empty())
    return Status::InvalidInput("no scan has both a ground-truth and an estimated pose");
  s->along_weak_rms_m = Rms(along);
  s->along_weak_rms_degenerate_m = Rms(along_degenerate);
  s->along_weak_final_m = along.back();
  s->along_weak_growth_per_100m =
      s->path_length_m > 0.0 ? (along.back() - along.front()) / s->path_length_m * 100.0 : kNaN;
  return Status::Ok();
}

}  // namespace

double AxisAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::min(1.0, std::abs(a.dot(b)) / (a.norm() * b.norm()));
  return std::acos(c) * 180.0 / M_PI;
}

StatusOr<DegeneracyScores> ScoreDegeneracy(const std::vector<DegeneracyLabel>& truth,
                                           const std::vector<DegeneracyLabel>& detected,
                                           double max_dt_s) {
  for (const DegeneracyLabel& l : truth)
    if (!l.weak_dir_world.allFinite() || std::abs(l.weak_dir_world.norm() - 1.0) > 1e-3)
      return Status::InvalidInput("a true weak direction is not a unit vector");
  StatusOr<std::vector<long>> partner = Partners(Stamps(truth), Stamps(detected), max_dt_s);
  if (!partner.ok()) return partner.status();
  DegeneracyScores s;
  std::vector<double> angles;
  for (size_t i = 0; i < truth.size(); ++i) {
    if ((*partner)[i] < 0) continue;
    const DegeneracyLabel& d = detected[static_cast<size_t>((*partner)[i])];
    ++s.matched;
    const bool t = truth[i].degenerate;
    if (t && d.degenerate) ++s.true_positive;
    if (!t && d.degenerate) ++s.false_positive;
    if (t && !d.degenerate) ++s.false_negative;
    if (!t && !d.degenerate) ++s.true_negative;
    if (t && d.degenerate && HasDirection(d.weak_dir_world))
      angles.push_back(AxisAngleDeg(truth[i].weak_dir_world, d.weak_dir_world));
  }
  s.precision = Ratio(s.true_positive, s.true_positive + s.false_positive);
  s.recall = Ratio(s.true_positive, s.true_positive + s.false_negative);
  s.angle_deg = ComputeStats(angles);
  if (angles.empty()) s.angle_deg.mean = s.angle_deg.median = kNaN;
  s.along_weak_rms_m = s.along_weak_rms_degenerate_m = s.along_weak_final_m = kNaN;
  s.along_weak_growth_per_100m = s.path_length_m = kNaN;
  return s;
}

StatusOr<DegeneracyScores> ScoreDegeneracy(const std::vector<DegeneracyLabel>& truth,
                                           const std::vector<DegeneracyLabel>& detected,
                                           const Trajectory& ground_truth,
                                           const Trajectory& estimate, const EvalOptions& options) {
  StatusOr<DegeneracyScores> s = ScoreDegeneracy(truth, detected, options.max_dt);
  if (!s.ok()) return s;
  s->path_length_m = 0.0;
  if (Status e = AddWeakDirectionError(truth, ground_truth, estimate, options, &*s); !e.ok())
    return e;
  return s;
}

}  // namespace rvlio
