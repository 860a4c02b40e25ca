#pragma once
// Scores a run's per-scan degeneracy detection against the simulator's true
// localizability (sim/localizability.h; docs/degeneracy_truth.md):
//  - precision and recall of "degenerate" over the scans matched by time
//    (positive = degenerate; NaN when undefined: nothing flagged / nothing
//    truly degenerate);
//  - the angle (deg) between the detected and the true weak translation
//    direction, sign-free acos|a . b|, over the scans both flag (and where the
//    detection gives a direction);
//  - the position error along the true weak direction: the estimate aligned
//    as `rvlio eval` aligns it (EvalOptions), e_k = p_est_aligned - p_gt at
//    each matched scan, projected on that scan's true weak direction w_k:
//    |e_k . w_k|. Reported: its RMS over all matched scans and over the truly
//    degenerate ones, its final value (last matched scan), and its growth
//    per 100 m of ground-truth path, (final - first) / path * 100.
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/eval/options.h"
#include "rvlio/eval/stats.h"

namespace rvlio {

// One scan's verdict: truth or detection.
struct DegeneracyLabel {
  TimeNs t_ns = 0;
  bool degenerate = false;
  // Weakest translation direction, world frame, unit; NaN or zero when the
  // detection gives none (a truth label always has one).
  Eigen::Vector3d weak_dir_world = Eigen::Vector3d::Zero();
};

struct DegeneracyScores {
  size_t matched = 0;  // scans matched by time (within EvalOptions::max_dt)
  size_t true_positive = 0, false_positive = 0, false_negative = 0, true_negative = 0;
  double precision = 0.0, recall = 0.0;  // NaN when undefined
  ErrorStats angle_deg;                  // over the scans both flag (count 0: none)
  // Along the true weak direction (m); NaN when no trajectory was given.
  size_t error_scans = 0;  // matched scans with a ground-truth and an estimated pose
  double along_weak_rms_m = 0.0;
  double along_weak_rms_degenerate_m = 0.0;  // over truly degenerate scans (NaN: none)
  double along_weak_final_m = 0.0;
  double along_weak_growth_per_100m = 0.0;  // m per 100 m of path (NaN: no path)
  double path_length_m = 0.0;
  std::vector<std::string> warnings;  // of the alignment
};

// Precision, recall and angles only. Error: a label stream empty, its stamps
// decreasing, no scan matched within max_dt_s, or a truth direction that is
// not a unit vector.
StatusOr<DegeneracyScores> ScoreDegeneracy(const std::vector<DegeneracyLabel>& truth,
                                           const std::vector<DegeneracyLabel>& detected,
                                           double max_dt_s);

// Everything: the scores above, then the error along the true weak direction
// of `estimate` (the run's trajectory) against `ground_truth`, aligned with
// `options` (errors as Evaluate's, eval/evaluate.h).
StatusOr<DegeneracyScores> ScoreDegeneracy(const std::vector<DegeneracyLabel>& truth,
                                           const std::vector<DegeneracyLabel>& detected,
                                           const Trajectory& ground_truth,
                                           const Trajectory& estimate, const EvalOptions& options);

// Sign-free angle between two directions (deg): acos(|a . b| / (|a| |b|)).
double AxisAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace rvlio
