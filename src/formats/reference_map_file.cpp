// Reading the inputs of `run --map` and `refine --map` (formats/reference_map_file.h).
#include "rvlio/formats/reference_map_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "rvlio/common/parallel.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/trajectory_io.h"

namespace rvlio {
namespace {

StatusOr<Trajectory> InitialPoses(const std::string& initial_pose,
                                  const std::string& initial_pose_tum) {
  if (!initial_pose.empty() && !initial_pose_tum.empty())
    return Status::InvalidInput("--initial-pose and --initial-pose-tum: give only one");
  if (!initial_pose_tum.empty()) {
    StatusOr<Trajectory> t = ReadTum(initial_pose_tum);
    if (!t.ok()) return Status::InvalidInput("--initial-pose-tum: " + t.status().message());
    if (t->empty())
      return Status::InvalidInput("--initial-pose-tum " + initial_pose_tum + ": holds no pose");
    return t;
  }
  if (initial_pose.empty() || initial_pose == "auto") return Trajectory();  // global search
  return ParseInitialPose(initial_pose);
}

// Distance from q to the nearest of `points` (once per run: a plain scan).
double NearestDistance(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& q) {
  double best2 = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : points) best2 = std::min(best2, (p - q).squaredNorm());
  return std::sqrt(best2);
}

// The warning for a map stored as float32 where float32 steps by a
// millimetre or more (empty otherwise): its points are no finer than that,
// whatever the local frame does.
std::string PrecisionWarning(const std::string& path, const PointCloudFile& cloud) {
  if (!cloud.xyz_single_precision) return "";
  double largest = 0.0;
  for (const Eigen::Vector3d& p : cloud.points) largest = std::max(largest, p.cwiseAbs().maxCoeff());
  if (largest < kFloat32MillimetreReach_m) return "";
  char text[320];
  std::snprintf(text, sizeof(text),
                "--map %s: x y z are float32 and reach %.0f m, where float32 steps by %.3g m: "
                "the map is no finer than that (store it with float64 x y z, or in a local frame)",
                path.c_str(), largest, Float32Step(largest));
  return text;
}

// The points of --map in their local frame (*origin, chosen from them): the
// file's coordinates, read in double precision, minus the origin.
StatusOr<std::vector<Eigen::Vector3d>> ReadReferencePoints(const std::string& path,
                                                           LocalOrigin* origin,
                                                           std::vector<std::string>* warnings) {
  PointCloudReadOptions read;
  read.keep_fields = false;
  StatusOr<PointCloudFile> cloud = ReadPointCloud(path, read);
  if (!cloud.ok()) return Status::InvalidInput("--map " + cloud.status().message());
  if (std::string w = PrecisionWarning(path, *cloud); !w.empty() && warnings != nullptr)
    warnings->push_back(w);
  *origin = ChooseLocalOrigin(cloud->points);
  origin->ToLocal(&cloud->points);
  return std::move(cloud->points);
}

// A reference its search structures could not hold whole is refused: a
// dropped point would silently leave a hole in the association and the
// deviation.
Status CheckReferenceReach(const std::string& path, const VoxelMap& structure,
                           const std::vector<Eigen::Vector3d>& p_ref) {
  if (Status s = CheckReach(structure, p_ref); !s.ok())
    return Status::InvalidInput("--map " + path + ": " + s.message());
  return Status::Ok();
}

// The two search structures of one reference cloud, built side by side (they
// only read p_ref): the thinned association map, and the full-resolution
// surface for the deviation when `surface` is given. These two builds are
// about a third of a large map's loading CPU time (perf, 10 M points).
// Refused (CheckReferenceReach) when either could not hold every point.
StatusOr<std::shared_ptr<const VoxelMap>> BuildReferenceStructures(
    const std::string& path, const std::vector<Eigen::Vector3d>& p_ref,
    const LocalizationOptions& options, std::shared_ptr<const ReferenceMap>* surface) {
  std::shared_ptr<const VoxelMap> association;
  ParallelFor(0, surface != nullptr ? 2 : 1, 2, [&](int structure, int) {
    if (structure == 0)
      association = MakeReferenceMap(p_ref, options);
    else
      *surface = std::make_shared<const ReferenceMap>(p_ref);
  });
  if (Status s = CheckReferenceReach(path, *association, p_ref); !s.ok()) return s;
  if (surface != nullptr)
    if (Status s = CheckReferenceReach(path, (*surface)->voxels(), p_ref); !s.ok()) return s;
  return association;
}

}  // namespace

StatusOr<std::shared_ptr<const VoxelMap>> LoadReferenceMap(
    const std::string& path, const LocalizationOptions& options,
    std::shared_ptr<const ReferenceMap>* surface, LocalOrigin* origin,
    std::vector<std::string>* warnings) {
  StatusOr<std::vector<Eigen::Vector3d>> p_ref = ReadReferencePoints(path, origin, warnings);
  if (!p_ref.ok()) return p_ref.status();
  return BuildReferenceStructures(path, *p_ref, options, surface);
}

StatusOr<std::shared_ptr<const ReferenceMap>> LoadReferenceSurface(
    const std::string& path, LocalOrigin* origin, std::vector<std::string>* warnings) {
  StatusOr<std::vector<Eigen::Vector3d>> p_ref = ReadReferencePoints(path, origin, warnings);
  if (!p_ref.ok()) return p_ref.status();
  auto surface = std::make_shared<const ReferenceMap>(*p_ref);
  if (Status s = CheckReferenceReach(path, surface->voxels(), *p_ref); !s.ok()) return s;
  return surface;
}

StatusOr<Trajectory> ParseInitialPose(const std::string& text) {
  std::istringstream in(text);
  std::string field;
  std::vector<double> v;
  bool ok = !text.empty() && text.back() != ',';
  while (ok && std::getline(in, field, ',')) {
    char* end = nullptr;
    const double x = std::strtod(field.c_str(), &end);
    ok = !field.empty() && end != field.c_str() && *end == '\0' && std::isfinite(x);
    v.push_back(x);
  }
  if (!ok || v.size() != 6)
    return Status::InvalidInput("--initial-pose '" + text +
                                "': expected x,y,z,roll_deg,pitch_deg,yaw_deg (six numbers)");
  const double deg = M_PI / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(v[5] * deg, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(v[4] * deg, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(v[3] * deg, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  StampedPose p;
  p.p_world_imu = Eigen::Vector3d(v[0], v[1], v[2]);
  p.q_world_imu = Eigen::Quaterniond(R);
  return Trajectory{p};
}

StatusOr<Localization> LoadLocalization(const std::string& map_path,
                                        const std::string& initial_pose,
                                        const std::string& initial_pose_tum,
                                        const OdometryOptions& options,
                                        std::shared_ptr<const ReferenceMap>* surface,
                                        std::vector<std::string>* warnings) {
  StatusOr<Trajectory> poses = InitialPoses(initial_pose, initial_pose_tum);
  if (!poses.ok()) return poses.status();
  Localization loc;
  StatusOr<std::vector<Eigen::Vector3d>> p_ref =
      ReadReferencePoints(map_path, &loc.origin, warnings);
  if (!p_ref.ok()) return p_ref.status();
  loc.origin.ToLocal(&*poses);  // the initial poses are given in the map's frame
  if (!poses->empty()) {
    const Eigen::Vector3d start = poses->front().p_world_imu;
    const double nearest_m = NearestDistance(*p_ref, start);
    if (!(nearest_m <= options.localization.max_start_distance)) {
      const Eigen::Vector3d start_user = loc.origin.ToUser(start);
      char text[320];
      std::snprintf(text, sizeof(text),
                    ": the nearest point is %.4g m from the initial position (%.3f, %.3f, %.3f), "
                    "more than localization.max_start_distance %.4g m: is the map in this frame "
                    "and in metres?",
                    nearest_m, start_user.x(), start_user.y(), start_user.z(),
                    options.localization.max_start_distance);
      return Status::InvalidInput("--map " + map_path + text);
    }
  }
  StatusOr<std::shared_ptr<const VoxelMap>> reference =
      BuildReferenceStructures(map_path, *p_ref, options.localization, surface);
  if (!reference.ok()) return reference.status();
  loc.reference = std::move(*reference);
  loc.initial_poses = std::move(*poses);
  return loc;
}

}  // namespace rvlio
