#pragma once
// Constructed point-to-plane constraint sets with a known degeneracy
// (test/degeneracy, test/smoother): a corridor (walls and floor/ceiling: one
// weak translation, along it), a pipe (one weak translation, the axis; and
// the rotation about it), a plane (two weak translations in the plane, and
// the rotation about its normal) and a closed room (none). Sensor at the
// origin, world = LiDAR = IMU frame: p_lidar = q_world.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"

namespace rvlio {
namespace test {

struct Scene {
  ConstraintList constraints;
  std::vector<int> weak_pose_indices;  // [dtheta 0-2, dp 3-5] with no information
  std::vector<Eigen::Vector3d> weak_translations;  // spanning the weak translation subspace
};

inline void AddPoint(const Eigen::Vector3d& p, const Eigen::Vector3d& n, ConstraintList* list) {
  Constraint c;
  c.p_lidar = p;
  c.normal_world = n.normalized();
  c.q_world = p;
  c.residual = 0.0;
  list->push_back(c);
}

// Walls y = +-3 and floor/ceiling z = +-3 along x in [-6, 6] (a section
// short enough that the roll is well constrained: a long thin one leaves
// the roll weak too, which X-ICP and the Schur test rightly report).
inline Scene Corridor() {
  Scene s;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> x(-6, 6), yz(-3, 3);
  for (int i = 0; i < 200; ++i) {
    AddPoint({x(rng), 3.0, yz(rng)}, {0, -1, 0}, &s.constraints);
    AddPoint({x(rng), -3.0, yz(rng)}, {0, 1, 0}, &s.constraints);
    AddPoint({x(rng), yz(rng), 3.0}, {0, 0, -1}, &s.constraints);
    AddPoint({x(rng), yz(rng), -3.0}, {0, 0, 1}, &s.constraints);
  }
  s.weak_pose_indices = {3};
  s.weak_translations = {Eigen::Vector3d::UnitX()};
  return s;
}

// A cylinder of radius 2 about the x axis.
inline Scene Pipe() {
  Scene s;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> x(-10, 10), angle(-M_PI, M_PI);
  for (int i = 0; i < 800; ++i) {
    const double a = angle(rng);
    const Eigen::Vector3d n(0.0, std::cos(a), std::sin(a));
    AddPoint(Eigen::Vector3d(x(rng), 0, 0) + 2.0 * n, -n, &s.constraints);
  }
  s.weak_pose_indices = {0, 3};  // rotation about and translation along the axis
  s.weak_translations = {Eigen::Vector3d::UnitX()};
  return s;
}

// The ground z = -1.5.
inline Scene Plane() {
  Scene s;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-10, 10);
  for (int i = 0; i < 800; ++i) AddPoint({xy(rng), xy(rng), -1.5}, {0, 0, 1}, &s.constraints);
  s.weak_pose_indices = {2, 3, 4};  // yaw, x, y
  s.weak_translations = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  return s;
}

// A closed box x = +-5, y = +-4, z = +-3.
inline Scene Room() {
  Scene s;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> x(-5, 5), y(-4, 4), z(-3, 3);
  for (int i = 0; i < 150; ++i) {
    for (double sign : {-1.0, 1.0}) {
      AddPoint({sign * 5.0, y(rng), z(rng)}, {-sign, 0, 0}, &s.constraints);
      AddPoint({x(rng), sign * 4.0, z(rng)}, {0, -sign, 0}, &s.constraints);
      AddPoint({x(rng), y(rng), sign * 3.0}, {0, 0, -sign}, &s.constraints);
    }
  }
  return s;
}

}  // namespace test
}  // namespace rvlio
