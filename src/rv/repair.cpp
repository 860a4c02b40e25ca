#include "rvlio/rv/repair.h"

#include "rvlio/common/check.h"

namespace rvlio {

bool ProjectIntoPlane(const Eigen::Vector3d& u, const Eigen::Vector3d& n_alpha,
                      Eigen::Vector3d* u_repaired) {
  // In-plane reading of Eq. (20) (see the header): remove the component along
  // n_alpha, then renormalize. The printed formula (u . n) n would keep only
  // the out-of-plane part.
  const Eigen::Vector3d v = u - u.dot(n_alpha) * n_alpha;
  const double norm = v.norm();
  if (!(norm > 1e-9)) return false;
  *u_repaired = v / norm;
  return true;
}

int RepairCoplanar(const RvOptions& options, const Pose3& T_world_lidar,
                   const Eigen::Vector3d& n_alpha, const RvWorkspace& ws,
                   ConstraintList* constraints) {
  RVLIO_CHECK(constraints != nullptr && ws.size() == static_cast<int>(constraints->size()));
  int repaired = 0;
  for (int i = 0; i < ws.size(); ++i) {
    if (ws.cls[i] != VectorClass::kCoplanar || ws.d[i] > options.eps1) continue;
    Eigen::Vector3d u_repaired;
    if (!ProjectIntoPlane(ws.u[i], n_alpha, &u_repaired)) continue;
    Constraint& c = (*constraints)[i];
    c.normal_world = u_repaired;
    // Alg. 3 step 6: residual of Eq. (3) with the repaired normal.
    c.residual = u_repaired.dot(T_world_lidar * c.p_lidar - c.q_world);
    c.role = RvRole::kRepaired;
    ++repaired;
  }
  return repaired;
}

}  // namespace rvlio
