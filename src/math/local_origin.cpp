#include "rvlio/math/local_origin.h"

#include <cmath>

#include <Eigen/Geometry>

namespace rvlio {
namespace {

LocalOrigin RoundedCentre(const Eigen::AlignedBox3d& box) {
  LocalOrigin origin;
  if (box.isEmpty()) return origin;
  const Eigen::Vector3d centre = box.center();
  for (int a = 0; a < 3; ++a)
    origin.t_user_local[a] = kLocalOriginGrid_m * std::round(centre[a] / kLocalOriginGrid_m);
  return origin;
}

}  // namespace

void LocalOrigin::ToLocal(std::vector<Eigen::Vector3d>* points) const {
  if (IsZero()) return;
  for (Eigen::Vector3d& p : *points) p -= t_user_local;
}

void LocalOrigin::ToUser(std::vector<Eigen::Vector3d>* points) const {
  if (IsZero()) return;
  for (Eigen::Vector3d& p : *points) p += t_user_local;
}

void LocalOrigin::ToLocal(Trajectory* trajectory) const {
  for (StampedPose& pose : *trajectory) pose.p_world_imu -= t_user_local;
}

void LocalOrigin::ToUser(Trajectory* trajectory) const {
  for (StampedPose& pose : *trajectory) pose.p_world_imu += t_user_local;
}

LocalOrigin ChooseLocalOrigin(const std::vector<Eigen::Vector3d>& p_user) {
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : p_user)
    if (p.allFinite()) box.extend(p);
  return RoundedCentre(box);
}

LocalOrigin ChooseLocalOrigin(const Trajectory& trajectory) {
  Eigen::AlignedBox3d box;
  for (const StampedPose& pose : trajectory)
    if (pose.p_world_imu.allFinite()) box.extend(pose.p_world_imu);
  return RoundedCentre(box);
}

}  // namespace rvlio
