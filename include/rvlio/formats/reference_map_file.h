#pragma once
// The inputs of localization in a reference map (`rvlio run --map`,
// `rvlio refine --map`; docs/survey.md): the reference point cloud and the
// initial pose.
#include <memory>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/odometry/options.h"
#include "rvlio/map/reference_map.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/odometry/reference.h"

namespace rvlio {

// The reference's search structure for association (MakeReferenceMap) from
// a PCD or PLY file (ReadPointCloud: x y z in metres, in double precision,
// validated), in the map's local frame: *origin is chosen from its points
// (ChooseLocalOrigin, math/local_origin.h) and subtracted from them, so a map
// in a national grid (UTM) is searched as precisely as one near zero.
// InvalidInput, one line starting with "--map PATH", when the file is
// missing, unreadable, truncated, empty or holds a non-finite point, and when
// a point lies beyond its search structures' reach from the local origin
// (CheckReach: 104.8 km along an axis for the deviation's 0.1 m voxels: a
// map larger than ~200 km, or a stray point far away). The file is only read.
// surface (when not null) receives the full cloud for the deviation
// (QueryReferenceSurface), from the same read, in the same local frame.
// warnings (when not null) receives one line, naming the file, for a map
// whose x y z are float32 where float32 steps by a millimetre or more
// (from 8192 m on: a UTM map stored as float32 holds only decimetres).
StatusOr<std::shared_ptr<const VoxelMap>> LoadReferenceMap(
    const std::string& path, const LocalizationOptions& options,
    std::shared_ptr<const ReferenceMap>* surface, LocalOrigin* origin,
    std::vector<std::string>* warnings);

// The full cloud alone, for the deviation (merge --map), in its local frame
// (*origin); errors and warnings as above.
StatusOr<std::shared_ptr<const ReferenceMap>> LoadReferenceSurface(
    const std::string& path, LocalOrigin* origin, std::vector<std::string>* warnings);

// "x,y,z,roll_deg,pitch_deg,yaw_deg" (metres, degrees; R = Rz(yaw) Ry(pitch)
// Rx(roll)) as a one-pose trajectory at t = 0. InvalidInput naming
// --initial-pose when malformed.
StatusOr<Trajectory> ParseInitialPose(const std::string& text);

// What `run --map` localizes in. initial_pose: ParseInitialPose's text;
// initial_pose_tum: a TUM file (one line: that pose; several: interpolated
// at the first scan). At most one of them; neither, or initial_pose "auto":
// the global search at the first scan (no initial poses). The initial poses
// are in the map's frame; the result holds them, the reference and *surface
// in the map's local frame (Localization::origin). Checks that the
// reference has points within localization.max_start_distance of the
// initial position (else the map is in another frame or unit). *surface
// receives the full cloud for the deviation (QueryReferenceSurface);
// warnings as LoadReferenceMap's.
StatusOr<Localization> LoadLocalization(const std::string& map_path,
                                        const std::string& initial_pose,
                                        const std::string& initial_pose_tum,
                                        const OdometryOptions& options,
                                        std::shared_ptr<const ReferenceMap>* surface,
                                        std::vector<std::string>* warnings);

}  // namespace rvlio
