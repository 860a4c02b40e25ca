#pragma once
// Synthetic constraint sets for the RV tests: a straight tunnel (plane normals
// perpendicular to the axis, small axial noise) plus a known subset of special
// constraint vectors with large axial components.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rvlio/constraints/constraint.h"
#include "rvlio/math/pose.h"

namespace rvlio::test {

inline Eigen::Vector3d RandomUnit(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Vector3d v(g(rng), g(rng), g(rng));
  while (v.norm() < 1e-6) v = Eigen::Vector3d(g(rng), g(rng), g(rng));
  return v.normalized();
}

inline Pose3 RandomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> ang(-M_PI, M_PI), pos(-50.0, 50.0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(ang(rng), RandomUnit(rng)).toRotationMatrix();
  return Pose3(R, Eigen::Vector3d(pos(rng), pos(rng), pos(rng)));
}

// A constraint with normal u whose point is p_lidar at pose T, plane point q
// chosen so that the residual is `offset` (q = p_world - offset u + tangent).
inline Constraint MakeConstraint(std::mt19937& rng, const Eigen::Vector3d& u, const Pose3& T) {
  std::uniform_real_distribution<double> pos(-15.0, 15.0), off(-0.2, 0.2), w(0.5, 2.0);
  Constraint c;
  c.p_lidar = Eigen::Vector3d(pos(rng), pos(rng), pos(rng));
  c.normal_world = u;
  const Eigen::Vector3d p_world = T * c.p_lidar;
  const double offset = off(rng);
  Eigen::Vector3d tangent = RandomUnit(rng);
  tangent -= tangent.dot(u) * u;
  c.q_world = p_world - offset * u + 0.3 * tangent;
  c.residual = u.dot(p_world - c.q_world);
  c.weight = w(rng);
  return c;
}

struct TunnelSet {
  ConstraintList list;
  std::vector<bool> is_scv;  // the known special constraint vectors
  Eigen::Vector3d axis;
  Pose3 T_world_lidar;
};

struct TunnelSpec {
  int num_coplanar = 1000;
  int num_scv = 40;
  double axial_noise = 0.02;   // std of the axial component of wall normals
  double scv_min_axial = 0.7;  // SCVs have |axial component| in [scv_min_axial, 1]
  // > 0: SCVs come from one structure (their in-plane direction has this
  // spread around one azimuth and their axial components one sign), so they
  // tilt the Alg. 1 plane; <= 0: uniform azimuth and random sign.
  double scv_azimuth_spread = 0.0;
};

inline TunnelSet MakeTunnelSet(std::mt19937& rng, const TunnelSpec& spec) {
  TunnelSet set;
  set.axis = RandomUnit(rng);
  set.T_world_lidar = RandomPose(rng);
  Eigen::Vector3d e1 = set.axis.unitOrthogonal();
  Eigen::Vector3d e2 = set.axis.cross(e1);
  std::normal_distribution<double> spread(0.0, 0.25), axial(0.0, spec.axial_noise);
  std::uniform_int_distribution<int> wall(0, 3);
  std::uniform_real_distribution<double> phi(-M_PI, M_PI), s(spec.scv_min_axial, 1.0);
  std::bernoulli_distribution coin(0.5);
  const double azimuth0 = phi(rng);
  std::normal_distribution<double> azimuth(azimuth0, std::max(spec.scv_azimuth_spread, 1e-9));
  const bool one_structure = spec.scv_azimuth_spread > 0.0;
  const int n = spec.num_coplanar + spec.num_scv;
  // Random interleaving of wall and special vectors.
  std::vector<bool> scv(n, false);
  for (int i = 0; i < spec.num_scv; ++i) scv[i] = true;
  std::shuffle(scv.begin(), scv.end(), rng);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d u;
    if (scv[i]) {
      const double a = s(rng) * (one_structure || coin(rng) ? 1.0 : -1.0);
      const double f = one_structure ? azimuth(rng) : phi(rng);
      u = a * set.axis + std::sqrt(1.0 - a * a) * (std::cos(f) * e1 + std::sin(f) * e2);
    } else {
      const double theta = wall(rng) * M_PI / 2.0 + spread(rng);
      const double a =
          std::max(-3.0 * spec.axial_noise, std::min(3.0 * spec.axial_noise, axial(rng)));
      u = (std::cos(theta) * e1 + std::sin(theta) * e2 + a * set.axis).normalized();
    }
    if (coin(rng)) u = -u;  // a normal's sign is arbitrary
    set.list.push_back(MakeConstraint(rng, u, set.T_world_lidar));
  }
  set.is_scv = scv;
  return set;
}

inline bool SameConstraint(const Constraint& a, const Constraint& b) {
  return a.p_lidar == b.p_lidar && a.normal_world == b.normal_world && a.q_world == b.q_world &&
         a.residual == b.residual && a.weight == b.weight && a.role == b.role;
}

inline bool SameList(const ConstraintList& a, const ConstraintList& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!SameConstraint(a[i], b[i])) return false;
  }
  return true;
}

}  // namespace rvlio::test
