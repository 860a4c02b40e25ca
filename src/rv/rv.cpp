#include "rvlio/rv/rv.h"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "rvlio/common/check.h"
#include "rvlio/rv/reinforce.h"
#include "rvlio/rv/repair.h"

namespace rvlio {

Eigen::Matrix3d PositionInformation(const ConstraintList& constraints, double sigma) {
  RVLIO_CHECK(sigma > 0.0);
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;  // upper triangle
  for (const Constraint& c : constraints) {
    const Eigen::Vector3d& u = c.normal_world;
    const Eigen::Vector3d wu = c.weight * u;
    if (!std::isfinite(wu.squaredNorm() + u.squaredNorm())) continue;
    xx += wu.x() * u.x();
    xy += wu.x() * u.y();
    xz += wu.x() * u.z();
    yy += wu.y() * u.y();
    yz += wu.y() * u.z();
    zz += wu.z() * u.z();
  }
  Eigen::Matrix3d info;
  info << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return info / (sigma * sigma);
}

double SmallestEigenvalue(const Eigen::Matrix3d& symmetric) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(symmetric, Eigen::EigenvaluesOnly);
  return solver.eigenvalues()(0);
}

RvReport ApplyRv(const RvOptions& options, const Pose3& T_world_lidar, ConstraintList* constraints,
                 RvWorkspace* ws) {
  RVLIO_CHECK(constraints != nullptr && ws != nullptr);
  RvReport report;
  report.num_constraints = static_cast<int>(constraints->size());
  if (options.enabled) {
    const CriterionResult criterion = EvaluateCriterion(options, *constraints, ws);  // Alg. 1
    report.n_alpha = criterion.fit.n_alpha;
    report.s_eigenvalues = criterion.fit.eigenvalues;
    report.num_usable = criterion.num_usable;
    report.num_coplanar = criterion.num_within_eps0;
    report.num_scv = criterion.num_usable - criterion.num_within_eps0;
    report.coplanar_fraction = criterion.coplanar_fraction;
    report.active = criterion.active;
    if (criterion.active) {
      const RefitResult refit = RefitPlane(options, criterion.S, criterion.fit, ws);  // Alg. 2
      report.n_alpha = refit.fit.n_alpha;
      report.iterations = refit.iterations;
      report.num_scv = refit.num_scv;
      report.num_coplanar = refit.num_coplanar;
      report.K = ReinforcementCoefficient(options, refit.num_scv, refit.num_coplanar);  // Eq. (19)
      if (options.reinforce && refit.num_scv > 0) {
        report.num_reinforced = ReinforceScv(report.K, *ws, constraints, options.reinforce_max_residual);
      }
      if (options.repair) {  // Alg. 3
        report.num_repaired =
            RepairCoplanar(options, T_world_lidar, refit.fit.n_alpha, *ws, constraints);
      }
    }
  }
  report.localizability = SmallestEigenvalue(PositionInformation(*constraints));
  return report;
}

RvReport ApplyRv(const RvOptions& options, const Pose3& T_world_lidar,
                 ConstraintList* constraints) {
  RvWorkspace ws;
  return ApplyRv(options, T_world_lidar, constraints, &ws);
}

}  // namespace rvlio
