#pragma once
// Multirotor-like flight: rest at the first waypoint for
// static_duration, then straight segments between waypoints, each with a
// jerk-limited speed ramp up ("shock": hover to forward acceleration), a
// cruise and a ramp down, and a hover at each waypoint; rest after the last.
// The attitude is that of a multirotor: body z along the required thrust
// a_world - g_world, body x towards a small, smooth yaw motion.
//
// Smoothness: the speed ramps use the septic smoothstep S(x) = 35x^4 - 84x^5 +
// 70x^6 - 20x^7, whose first three derivatives vanish at both ends, so position
// is C^4, acceleration C^2 and the angular rate (which depends on the jerk)
// C^1: the IMU signal is continuous and numerically integrable.
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"
#include "rvlio/math/pose.h"
#include "rvlio/sim/options.h"

namespace rvlio::sim {

// The true IMU state at t_ns.
struct TruthState {
  TimeNs t_ns = 0;
  Pose3 T_world_imu;
  Eigen::Vector3d v_world_imu = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d a_world_imu = Eigen::Vector3d::Zero();  // m/s^2, kinematic acceleration
  Eigen::Vector3d w_imu = Eigen::Vector3d::Zero();        // rad/s, angular rate in the IMU frame
};

// "x,y,z; x,y,z; ..." -> points. InvalidInput names the bad item.
StatusOr<std::vector<Eigen::Vector3d>> ParseWaypoints(const std::string& text);

class FlightTrajectory {
 public:
  // waypoints: at least one; t0_ns: time of the first sample (tau = 0).
  FlightTrajectory(std::vector<Eigen::Vector3d> waypoints, const SimTrajectoryOptions& options,
                   double gravity, TimeNs t0_ns, uint64_t seed);

  TruthState At(TimeNs t_ns) const;
  // Position and its first three derivatives at tau seconds after t0.
  void Translation(double tau, Eigen::Vector3d* p, Eigen::Vector3d* v, Eigen::Vector3d* a,
                   Eigen::Vector3d* jerk) const;
  // Yaw (rad) and its rate at tau.
  void Yaw(double tau, double* yaw, double* yaw_rate) const;
  // The sway rotation vector phi (body frame) and its time derivative.
  void Sway(double tau, Eigen::Vector3d* phi, Eigen::Vector3d* phi_rate) const;

  const std::vector<Eigen::Vector3d>& waypoints() const { return waypoints_; }
  // Seconds after t0 at which waypoint i is reached (0 for the first).
  double ArrivalTime(size_t i) const { return arrival_s_[i]; }
  double MotionEnd() const { return arrival_s_.back(); }
  // The rests on the floor, s after t0: the static phase and, with
  // trajectory.landing_time, each landing (the last one open-ended).
  const std::vector<std::pair<double, double>>& landed() const { return landed_s_; }
  bool Landed(double tau) const;
  bool stop_and_go() const { return options_.landing_time > 0.0; }
  TimeNs t0_ns() const { return t0_ns_; }
  double gravity() const { return gravity_; }
  // Points along the path every `step` m (for feature clearance).
  std::vector<Eigen::Vector3d> SamplePath(double step) const;

 private:
  struct Segment {
    double t_begin = 0.0;  // s after t0
    double ramp = 0.0;     // s per ramp
    double cruise = 0.0;   // s at constant speed
    double speed = 0.0;    // m/s
    double length = 0.0;   // m
    Eigen::Vector3d from = Eigen::Vector3d::Zero();
    Eigen::Vector3d dir = Eigen::Vector3d::UnitX();
    double t_end() const { return t_begin + 2.0 * ramp + cruise; }
  };
  void AlongSegment(const Segment& s, double tau, double* d, double* v, double* a, double* j) const;

  std::vector<Eigen::Vector3d> waypoints_;
  std::vector<Segment> segments_;
  std::vector<double> arrival_s_;
  std::vector<std::pair<double, double>> landed_s_;
  SimTrajectoryOptions options_;
  double gravity_;
  TimeNs t0_ns_;
  double yaw_phase_[2] = {0.0, 0.0};
  double sway_phase_[3] = {0.0, 0.0, 0.0};
};

}  // namespace rvlio::sim
