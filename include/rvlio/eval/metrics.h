#pragma once
// Trajectory error metrics with the definitions of evo (evo.core.metrics).
// All functions take matched trajectories (pose k of `ref` and `est` form a
// pair, equal sizes) where `est` is already aligned.
#include <cstddef>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/eval/stats.h"

namespace rvlio {

// APE translation: ||t_ref_k - t_est_k|| (m).
std::vector<double> ApeTranslationErrors(const Trajectory& ref, const Trajectory& est);
// APE rotation: angle of Q_ref_k^-1 Q_est_k in degrees, in [0, 180].
std::vector<double> ApeRotationErrorsDeg(const Trajectory& ref, const Trajectory& est);

// Rotation angle of a quaternion in radians, in [0, pi], accurate for small
// angles (2 atan2(|v|, |w|)).
double RotationAngle(const Eigen::Quaterniond& q);

enum class RpeUnit { kFrames, kMeters };

struct RpeOptions {
  double delta = 1.0;  // frames (whole number >= 1) or metres (> 0)
  RpeUnit unit = RpeUnit::kFrames;
};

// evo's consecutive pairs (all_pairs = false), chosen on the estimate:
// frames: ids 0, d, 2d, ... and pairs of consecutive ids;
// meters: the ids where the path travelled since the previous id (starting at
// pose 0, which is itself not an id) reaches delta, pairs of consecutive ids.
std::vector<std::pair<size_t, size_t>> RpePairs(const Trajectory& est, const RpeOptions& options);

struct RpeResult {
  size_t pairs = 0;
  ErrorStats trans_m;  // ||translation(E_i)||
  ErrorStats rot_deg;  // angle(E_i)
};

// E_i = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q = reference, P = estimate. Error when
// the delta leaves no pair (as evo does).
StatusOr<RpeResult> ComputeRpe(const Trajectory& ref, const Trajectory& est,
                               const RpeOptions& options);

// ||t_ref_last - t_est_last|| (m) of the last matched pair.
double EndPointError(const Trajectory& ref, const Trajectory& est);

struct AlongAxisError {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // principal axis of the reference positions
  double rmse_m = 0.0;                              // of a_k = axis . (t_est_k - t_ref_k)
  double max_abs_m = 0.0;                           // max |a_k|
  std::vector<double> errors_m;                     // a_k at each matched pose, in order
};

// Position error projected on the principal axis (eigenvector of the largest
// eigenvalue of the centred covariance) of the reference positions: the drift
// along a tunnel.
AlongAxisError ComputeAlongAxisError(const Trajectory& ref, const Trajectory& est);

}  // namespace rvlio
