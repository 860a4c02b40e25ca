#pragma once
// The constraint record both estimators consume and the RV module edits
// (docs/design.md "The shared measurement model"): one point-to-plane correspondence of one scan
// point.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rvlio {

enum class RvRole : uint8_t {
  kPlain = 0,     // untouched by RV (RV inactive, or coplanar with d_i > eps1)
  kScv = 1,       // special constraint vector: weight scaled by 1/K (Alg. 2)
  kRepaired = 2,  // normal projected into plane alpha (Alg. 3)
};

struct Constraint {
  Eigen::Vector3d p_lidar = Eigen::Vector3d::Zero();       // deskewed point, LiDAR frame, m
  Eigen::Vector3d normal_world = Eigen::Vector3d::UnitZ();  // unit plane normal u (world)
  Eigen::Vector3d q_world = Eigen::Vector3d::Zero();        // a point on the plane (world), m
  double residual = 0.0;  // r = u^T (p_world - q), m, at the pose it was associated with
  double weight = 1.0;    // information multiplier: R_i = sigma^2 / weight (RV: 1/K for SCVs)
  RvRole role = RvRole::kPlain;
};

using ConstraintList = std::vector<Constraint>;

// A pose has six degrees of freedom: fewer point-to-plane constraints cannot
// determine it, so a scan with fewer is not used for its pose (the IESKF
// keeps the prediction, the sliding window adds no plane factor for it).
constexpr int kMinPoseConstraints = 6;

}  // namespace rvlio
