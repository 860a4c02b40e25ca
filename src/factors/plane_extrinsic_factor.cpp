#include "rvlio/factors/plane_extrinsic_factor.h"

#include <cmath>
#include <utility>

#include <Eigen/Core>

#include "rvlio/common/check.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/factors/manifolds.h"
#include "rvlio/factors/plane_factor.h"

namespace rvlio {

PlaneExtrinsicFactor::PlaneExtrinsicFactor(ConstraintList constraints, double sigma_m)
    : constraints_(std::move(constraints)) {
  inv_sigma_ = CheckedPlaneInvSigma(constraints_, sigma_m);
  set_num_residuals(num_constraints());
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
  mutable_parameter_block_sizes()->push_back(PoseBlock::kNumParams);
}

bool PlaneExtrinsicFactor::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  const Pose3 T_world_imu = PoseBlock::FromArray(parameters[0]).ToPose3();
  const Pose3 T_imu_lidar = PoseBlock::FromArray(parameters[1]).ToPose3();
  const int n = num_constraints();
  const bool want_pose = jacobians != nullptr && jacobians[0] != nullptr;
  const bool want_ext = jacobians != nullptr && jacobians[1] != nullptr;
  using RowMajorX6 = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;
  RowMajorX6 J_pose(want_pose ? n : 0, 6), J_ext(want_ext ? n : 0, 6);
  Eigen::Matrix<double, 1, 12> h;
  for (int i = 0; i < n; ++i) {
    const Constraint& c = constraints_[i];
    const double s = std::sqrt(c.weight) * inv_sigma_;
    const double r = PointToPlaneResidualWithExtrinsics(c, T_world_imu, T_imu_lidar,
                                                        want_pose || want_ext ? &h : nullptr);
    residuals[i] = s * r;
    if (want_pose) J_pose.row(i) = s * h.leftCols<6>();
    if (want_ext) J_ext.row(i) = s * h.rightCols<6>();
  }
  if (want_pose) PoseTangentToAmbientJacobian(parameters[0], J_pose, jacobians[0]);
  if (want_ext) PoseTangentToAmbientJacobian(parameters[1], J_ext, jacobians[1]);
  return true;
}

}  // namespace rvlio
