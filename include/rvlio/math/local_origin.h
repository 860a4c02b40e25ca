#pragma once
// The local frame: the frame of the user's data, translated so that its
// origin lies near the data (docs/design.md "Conventions").
//
// Reference maps, control surveys and initial poses often come in a national
// grid: UTM eastings near 500 000 m, northings up to 10 000 000 m. There a
// float32 keeps only decimetres (the voxel maps store float32 points, map.pcd
// wrote float32), and the voxel maps' packed keys reach only ~10^5 voxels from
// the origin (map/voxel_map.h, VoxelMapReach). So a cloud or a pose in the
// user's frame is moved into the local frame where it enters (`run --map`,
// `refine`, `merge`, `eval --map`), the estimation and every search run
// there, and the offset is added back in double precision to what goes out.
// Only a translation: the local frame's axes are the user frame's (z up stays
// up, a gravity-aligned frame stays gravity-aligned).
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/types.h"

namespace rvlio {

// The local origin is the data's median rounded to a multiple of this, per
// axis: a readable offset, and data within half of it of the user frame's
// origin (the simulator's, a run without a map) keep the user frame (zero
// offset), so their results do not change.
constexpr double kLocalOriginGrid_m = 1000.0;

// Below this magnitude a float32 coordinate is within 0.25 mm of the value
// (its steps are 0.5 mm or finer); from it on, a coordinate needs float64 to
// keep millimetres (map.pcd is written so: outputs/run_outputs.h).
constexpr double kFloat32MillimetreReach_m = 8192.0;
// The spacing of float32 values at magnitude |v| (m): 0.5 at a northing of
// 5.4e6 m, 0.03125 at an easting of 5e5 m.
double Float32Step(double v);

struct LocalOrigin {
  // The local frame's origin in the user frame, m: p_user = p_local + t_user_local.
  Eigen::Vector3d t_user_local = Eigen::Vector3d::Zero();

  bool IsZero() const { return t_user_local.isZero(0.0); }
  Eigen::Vector3d ToLocal(const Eigen::Vector3d& p_user) const { return p_user - t_user_local; }
  Eigen::Vector3d ToUser(const Eigen::Vector3d& p_local) const { return p_local + t_user_local; }
  void ToLocal(std::vector<Eigen::Vector3d>* points) const;
  void ToUser(std::vector<Eigen::Vector3d>* points) const;
  // Positions of the poses (T_world_imu); orientations are the same in both frames.
  void ToLocal(Trajectory* trajectory) const;
  void ToUser(Trajectory* trajectory) const;
};

// The multiple of kLocalOriginGrid_m nearest to the median of the finite
// points, per axis (of an even subsample of at most 65536 of them; zero when
// none is finite). The median rather than the centre of the bounding box: a
// stray point (a survey's (0, 0, 0), a blunder 200 km away) does not move the
// origin away from where the data are, and the bulk of the data gets the
// finest float32 resolution.
LocalOrigin ChooseLocalOrigin(const std::vector<Eigen::Vector3d>& p_user);
// The same over the positions of a trajectory.
LocalOrigin ChooseLocalOrigin(const Trajectory& trajectory);

}  // namespace rvlio
