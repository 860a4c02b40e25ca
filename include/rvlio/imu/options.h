#pragma once
// IMU input and noise model (continuous-time densities).
#include <string>

#include "rvlio/common/options.h"

namespace rvlio {

struct ImuOptions {
  std::string topic = "/imu/data";
  double gyro_noise_density = 7.9e-5;      // rad/s/sqrt(Hz)
  double accel_noise_density = 9.8e-4;     // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 1.0e-5;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 1.0e-4;  // m/s^3/sqrt(Hz)
  double gravity = 9.81;                   // m/s^2, magnitude used when not estimated
  std::string accel_unit = "mps2";         // mps2 | g: unit the driver reports acceleration in
  double init_duration = 1.0;              // s of IMU data used for static initialization
  double max_gap = 0.1;                    // s, IMU gap above which a warning is counted

  template <class V>
  void Visit(V& v) {
    v.Field("topic", topic, Spec().Help("sensor_msgs/Imu topic in the bag"));
    v.Field("gyro_noise_density", gyro_noise_density, Spec().Unit("rad/s/sqrt(Hz)").Positive());
    v.Field("accel_noise_density", accel_noise_density, Spec().Unit("m/s^2/sqrt(Hz)").Positive());
    v.Field("gyro_bias_random_walk", gyro_bias_random_walk, Spec().Unit("rad/s^2/sqrt(Hz)").Positive());
    v.Field("accel_bias_random_walk", accel_bias_random_walk, Spec().Unit("m/s^3/sqrt(Hz)").Positive());
    v.Field("gravity", gravity, Spec().Unit("m/s^2").Range(9.0, 10.5).Help("gravity magnitude"));
    v.Field("accel_unit", accel_unit, Spec().Choices({"mps2", "g"}).Help("unit of the reported acceleration"));
    v.Field("init_duration", init_duration, Spec().Unit("s").Range(0.05, 60.0)
                                              .Help("IMU data used for static alignment"));
    v.Field("max_gap", max_gap, Spec().Unit("s").Positive().Help("IMU gap reported as a warning"));
  }
  Status Validate() { return ValidateFields(*this, "imu"); }
};

}  // namespace rvlio
