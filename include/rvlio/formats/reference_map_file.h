#pragma once
// The inputs of localization in a reference map (`rvlio run --map`,
// `rvlio refine --map`; docs/survey.md): the reference point cloud and the
// initial pose.
#include <memory>
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/odometry/options.h"
#include "rvlio/map/reference_map.h"
#include "rvlio/odometry/reference.h"

namespace rvlio {

// The reference's search structure for association (MakeReferenceMap) from
// a PCD or PLY file (ReadPointCloud:
// x y z in metres, validated). InvalidInput, one line starting with
// "--map PATH", when the file is missing, unreadable, truncated, empty or
// holds a non-finite point. The file is only read.
// surface (when not null) receives the full cloud for the deviation
// (QueryReferenceSurface), from the same read.
StatusOr<std::shared_ptr<const VoxelMap>> LoadReferenceMap(
    const std::string& path, const LocalizationOptions& options,
    std::shared_ptr<const ReferenceMap>* surface = nullptr);

// The full cloud alone, for the deviation (merge --map); errors as above.
StatusOr<std::shared_ptr<const ReferenceMap>> LoadReferenceSurface(const std::string& path);

// "x,y,z,roll_deg,pitch_deg,yaw_deg" (metres, degrees; R = Rz(yaw) Ry(pitch)
// Rx(roll)) as a one-pose trajectory at t = 0. InvalidInput naming
// --initial-pose when malformed.
StatusOr<Trajectory> ParseInitialPose(const std::string& text);

// What `run --map` localizes in. initial_pose: ParseInitialPose's text;
// initial_pose_tum: a TUM file (one line: that pose; several: interpolated
// at the first scan). At most one of them; neither, or initial_pose "auto":
// the global search at the first scan (no initial poses). Checks that the
// reference has points within localization.max_start_distance of the
// initial position (else the map is in another frame or unit). *surface
// receives the full cloud for the deviation (QueryReferenceSurface).
StatusOr<Localization> LoadLocalization(const std::string& map_path,
                                        const std::string& initial_pose,
                                        const std::string& initial_pose_tum,
                                        const OdometryOptions& options,
                                        std::shared_ptr<const ReferenceMap>* surface);

}  // namespace rvlio
