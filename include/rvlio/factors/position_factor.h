#pragma once
// PositionFactor: a point rigidly attached to the IMU, measured in the world
// (survey) frame at one time (a control mark under the device at rest, a GNSS
// antenna, a wall target seen by a scan; refine/control.h, docs/control.md).
//
// The time lies between two pose blocks a and b (states at scan ends) at the
// fraction alpha in [0, 1]; the point's world position is interpolated
// linearly between where each pose carries it:
//   p(x) = (1 - alpha) (p_a + R_a l) + alpha (p_b + R_b l),
//   r = W (p(x) - z),
// l = p_imu_point (the point in the IMU frame), z the measured position, W
// the square-root information (diag(1/sigma) for independent axes). With
// one pose block (alpha 0) it is r = W (p_a + R_a l - z).
// Tangent Jacobian (right perturbation R Exp(d), p + dp) of pose i with
// weight w_i (1 - alpha, alpha):
//   d r / d [d, dp] = w_i W [ -R_i [l]x , I3 ].
// The robust kernel is the caller's (a ceres::LossFunction on the block).
#include <Eigen/Core>
#include <ceres/cost_function.h>
#include <ceres/sized_cost_function.h>

#include "rvlio/factors/parameter_blocks.h"

namespace rvlio {

class PositionFactor final : public ceres::CostFunction {
 public:
  // One pose block.
  PositionFactor(const Eigen::Vector3d& p_imu_point, const Eigen::Vector3d& z_world,
                 const Eigen::Matrix3d& sqrt_information);
  // Two pose blocks (a, b), alpha in [0, 1].
  PositionFactor(const Eigen::Vector3d& p_imu_point, const Eigen::Vector3d& z_world,
                 const Eigen::Matrix3d& sqrt_information, double alpha);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  // The point's world position carried by the poses (the unwhitened p(x)).
  Eigen::Vector3d Predict(double const* const* parameters) const;

 private:
  Eigen::Vector3d p_imu_point_, z_world_;
  Eigen::Matrix3d sqrt_information_;
  double alpha_ = 0.0;
  int blocks_ = 1;
};

// ZeroVelocityFactor: the device at rest (a stop-and-go landing): the
// velocity of a speed-bias block (9) is zero,
//   r = v_world_imu / sigma_v,   d r / d sb = [I3 / sigma_v, 0, 0].
class ZeroVelocityFactor final : public ceres::SizedCostFunction<3, 9> {
 public:
  explicit ZeroVelocityFactor(double sigma_v);  // m/s, > 0
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  double inv_sigma_;
};

}  // namespace rvlio
