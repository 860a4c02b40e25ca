#pragma once
// Iterated error-state Kalman filter (paper Section 2, Eq. 1-3).
#include "rvlio/common/options.h"

namespace rvlio {

struct IeskfOptions {
  int max_iterations = 4;             // iterated update cap per scan
  double convergence_eps = 1e-3;      // increment norm (rad and m) that ends the iteration
  bool estimate_extrinsics = false;   // extrinsics fixed by default (paper 3.2)
  double init_pos_std = 1e-3;         // m, initial position std
  double init_rot_std = 1e-3;         // rad
  double init_vel_std = 0.1;          // m/s
  double init_bias_gyro_std = 1e-3;   // rad/s
  double init_bias_acc_std = 0.05;    // m/s^2
  double init_extrinsic_rot_std = 0.05;  // rad, prior std of R_imu_lidar (estimate_extrinsics)
  double init_extrinsic_pos_std = 0.1;   // m, prior std of t_imu_lidar (estimate_extrinsics)
  double init_gravity_std = 1e-4;     // m/s^2
  // Random walk of the estimated extrinsic axes (estimate_extrinsics).
  double extrinsic_rot_random_walk = 1e-4;  // rad/sqrt(s)
  double extrinsic_pos_random_walk = 2e-4;  // m/sqrt(s)

  template <class V>
  void Visit(V& v) {
    v.Field("max_iterations", max_iterations, Spec().Range(1, 50));
    v.Field("convergence_eps", convergence_eps, Spec().Positive());
    v.Field("estimate_extrinsics", estimate_extrinsics, Spec().Help(
        "estimate R_imu_lidar, t_imu_lidar online; an axis the motion does not excite stays at "
        "the configured value (summary.json: extrinsic)"));
    v.Field("init_pos_std", init_pos_std, Spec().Unit("m").Positive());
    v.Field("init_rot_std", init_rot_std, Spec().Unit("rad").Positive());
    v.Field("init_vel_std", init_vel_std, Spec().Unit("m/s").Positive());
    v.Field("init_bias_gyro_std", init_bias_gyro_std, Spec().Unit("rad/s").Positive());
    v.Field("init_bias_acc_std", init_bias_acc_std, Spec().Unit("m/s^2").Positive());
    v.Field("init_extrinsic_rot_std", init_extrinsic_rot_std, Spec().Unit("rad").Positive()
        .Help("prior std of the configured extrinsic rotation when estimate_extrinsics is on"));
    v.Field("init_extrinsic_pos_std", init_extrinsic_pos_std, Spec().Unit("m").Positive()
        .Help("prior std of the configured extrinsic translation when estimate_extrinsics is on"));
    v.Field("init_gravity_std", init_gravity_std, Spec().Unit("m/s^2").Positive());
    v.Field("extrinsic_rot_random_walk", extrinsic_rot_random_walk,
            Spec().Unit("rad/sqrt(s)").Range(0.0, 1.0).Help(
                "process noise of each estimated extrinsic rotation axis (estimate_extrinsics)"));
    v.Field("extrinsic_pos_random_walk", extrinsic_pos_random_walk,
            Spec().Unit("m/sqrt(s)").Range(0.0, 1.0).Help(
                "process noise of each estimated extrinsic translation axis (estimate_extrinsics)"));
  }
  Status Validate() { return ValidateFields(*this, "ieskf"); }
};

}  // namespace rvlio
