#pragma once
// The localizability a scan's true geometry allows (docs/degeneracy_truth.md).
//
// For the points the estimator keeps (its voxel grid, lidar/preprocess.h, on
// the simulated scan), take the true hit point p and the true unit surface
// normal n there (world frame). A point-to-plane residual n^T (p - q) has the
// Jacobian J = [ (r x n)^T  n^T ] with respect to a rotation (rad, about the
// world axes through the sensor) and a translation (m) of the sensor pose,
// r = p - sensor position. Per point with sigma = 1 and normalized by the
// point count N:
//   translation information  H_tt = (1/N) sum n n^T  (eigenvalues in [0, 1], sum 1),
//   pose information         H    = (1/N) sum J^T J  (6x6, rotation first).
// The weak translation direction is the eigenvector of H_tt's smallest
// eigenvalue; the scan is degenerate when lambda_min / lambda_max of H_tt is
// below `degenerate_ratio`. No I/O: `rvlio simulate` writes the records.
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/sim/lidar_sim.h"
#include "rvlio/sim/options.h"
#include "rvlio/sim/world.h"

namespace rvlio::sim {

using Vector6d = Eigen::Matrix<double, 6, 1>;

struct ScanLocalizability {
  TimeNs t_ns = 0;  // true time of the scan end (the stamp of the estimator's pose)
  int points = 0;   // kept points with a true normal
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();      // of H_tt, ascending
  Eigen::Vector3d weak_dir_world = Eigen::Vector3d::UnitX();  // unit, of eigenvalues[0]
  double ratio = 0.0;                     // eigenvalues[0] / eigenvalues[2] (0 with no points)
  double pose_eigenvalue_min = 0.0;       // smallest eigenvalue of H
  Vector6d pose_weak = Vector6d::Zero();  // its unit eigenvector (rx ry rz tx ty tz)
  bool degenerate = true;                 // ratio < degenerate_ratio (or no points)
};

// The information of a set of (point, sensor, normal) samples; hits with a
// zero normal are skipped. Signs: the weak direction's largest component is
// positive, so is the pose eigenvector's.
ScanLocalizability LocalizabilityOf(const std::vector<SurfaceHit>& hits,
                                    const std::vector<int>& indices, double degenerate_ratio);

// Per scan: the estimator's voxel grid on the simulated scan, the true
// normals of the kept points (World::Normal), then LocalizabilityOf them.
// Owns the grid's workspace.
class LocalizabilityTruth {
 public:
  // `lidar`: the simulated sensor's range limits (the estimator's crop).
  LocalizabilityTruth(const SimLocalizabilityOptions& options, const SimLidarOptions& lidar);
  // Fills the normals of the kept hits.
  ScanLocalizability Compute(const World& world, const Scan& scan, std::vector<SurfaceHit>* hits);

 private:
  double degenerate_ratio_;
  ScanPreprocessor preprocessor_;
  std::vector<int> kept_;
};

}  // namespace rvlio::sim
