// Localization in a fixed reference map: the reference's search structure
// and the coarse-to-fine alignment of the first scan (odometry/reference.h).
#include "rvlio/odometry/reference.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <tuple>
#include <unordered_set>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "rvlio/constraints/plane_association.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/constraints/robust_kernel.h"
#include "rvlio/map/voxel_key.h"
#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The association of one alignment stage: residuals up to radius_m, and
// neighbours searched at least that far.
ConstraintOptions StageOptions(const ConstraintOptions& base, double radius_m) {
  ConstraintOptions o = base;
  o.max_residual = radius_m;
  o.max_neighbor_distance = std::max(base.max_neighbor_distance, radius_m);
  return o;
}

// Normal equations of the weighted point-to-plane residuals at T_ref_imu.
void Accumulate(const ConstraintList& constraints, const Pose3& T_ref_imu,
                const Pose3& T_imu_lidar, bool weighted, Matrix6d* H, Vector6* b) {
  H->setZero();
  b->setZero();
  Eigen::Matrix<double, 1, 6> J;
  for (const Constraint& c : constraints) {
    const double r = PointToPlaneResidual(c, T_ref_imu, T_imu_lidar, &J);
    const double w = weighted ? c.weight : 1.0;
    *H += w * J.transpose() * J;
    *b += w * J.transpose() * r;
  }
}

// One Gauss-Newton step with Huber weights (delta: a quarter of the radius).
// False when the scan has too few constraints to fix a pose.
bool GaussNewtonStep(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_imu_lidar,
                     const VoxelMap& reference, const ConstraintOptions& stage, double radius_m,
                     ConstraintList* constraints, Pose3* T_ref_imu) {
  AssociateWith(p_lidar, *T_ref_imu * T_imu_lidar, reference, stage, constraints, nullptr);
  if (static_cast<int>(constraints->size()) < kMinPoseConstraints) return false;
  ApplyHuberWeights(0.25 * radius_m, constraints);
  Matrix6d H;
  Vector6 b;
  Accumulate(*constraints, *T_ref_imu, T_imu_lidar, true, &H, &b);
  H.diagonal().array() += 1e-6 * std::max(1.0, H.diagonal().maxCoeff());  // gauge along unseen axes
  const Vector6 dx = -H.ldlt().solve(b);
  if (!dx.allFinite()) return false;
  T_ref_imu->R = T_ref_imu->R * so3::Exp(dx.head<3>());
  T_ref_imu->t += dx.tail<3>();
  return true;
}

// The position block of the covariance (the information's inverse, with a
// tiny ridge so that an unfixed axis gives a huge but finite variance).
void WeakestAxis(const Matrix6d& information, double lidar_noise_m, ReferenceAlignment* a) {
  Matrix6d info = information;
  info.diagonal().array() += 1e-9 * std::max(1.0, info.diagonal().maxCoeff());
  const Eigen::Matrix3d cov_p = info.ldlt().solve(Matrix6d::Identity()).block<3, 3>(3, 3);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov_p);
  a->weakest_axis = eig.eigenvectors().col(2);
  const double var_m2 = eig.eigenvalues()(2);
  a->weakest_axis_constraints = var_m2 > 0.0 ? lidar_noise_m * lidar_noise_m / var_m2 : 0.0;
}

// Grid cells (edge step_m) holding points of `coarse`.
std::unordered_set<VoxelKey, VoxelKeyHash> OccupiedCells(const VoxelMap& coarse, double step_m) {
  std::unordered_set<VoxelKey, VoxelKeyHash> cells;
  coarse.ForEachPoint([&](const Eigen::Vector3d& p) { cells.insert(KeyOf(p, 1.0 / step_m)); });
  return cells;
}

// Share of p_lidar's points with an accepted plane of `search` at T_ref_imu.
template <class Search>
double OverlapWith(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_ref_imu,
                   const Pose3& T_imu_lidar, const Search& search,
                   const ConstraintOptions& constraints) {
  if (p_lidar.empty()) return 0.0;
  ConstraintList list;
  AssociationStats stats;
  AssociateWith(p_lidar, T_ref_imu * T_imu_lidar, search, constraints, &list, &stats);
  return static_cast<double>(stats.num_accepted) / static_cast<double>(p_lidar.size());
}

// Centres of the empty cells next to an occupied one: where a sensor that
// sees the reference's surfaces can be.
std::vector<Eigen::Vector3d> FreeCellsNearSurfaces(
    const std::unordered_set<VoxelKey, VoxelKeyHash>& occupied, double step_m) {
  std::unordered_set<VoxelKey, VoxelKeyHash> free;
  for (const VoxelKey& c : occupied)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const VoxelKey n{c.x + dx, c.y + dy, c.z + dz};
          if (!occupied.count(n)) free.insert(n);
        }
  std::vector<VoxelKey> keys(free.begin(), free.end());
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  std::vector<Eigen::Vector3d> centres;
  centres.reserve(keys.size());
  for (const VoxelKey& k : keys)
    centres.emplace_back((k.x + 0.5) * step_m, (k.y + 0.5) * step_m, (k.z + 0.5) * step_m);
  return centres;
}

// Candidate positions near an initial position: a horizontal lattice of
// half the search step (finer than the alignment's reach of about a metre)
// within start_check_radius, at the initial height.
std::vector<Eigen::Vector3d> PositionsAround(const Eigen::Vector3d& p,
                                             const LocalizationOptions& options) {
  const double step_m = 0.5 * options.search_step;
  const int n = static_cast<int>(std::floor(options.start_check_radius / step_m));
  std::vector<Eigen::Vector3d> positions;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      if (std::hypot(i * step_m, j * step_m) <= options.start_check_radius)
        positions.push_back(p + Eigen::Vector3d(i * step_m, j * step_m, 0.0));
  return positions;
}

// Every n-th point, about `count` in all.
std::vector<Eigen::Vector3d> Subsample(const std::vector<Eigen::Vector3d>& p, size_t count) {
  const size_t stride = std::max<size_t>(1, p.size() / std::max<size_t>(1, count));
  std::vector<Eigen::Vector3d> out;
  for (size_t i = 0; i < p.size(); i += stride) out.push_back(p[i]);
  return out;
}

// Two places, not one: more than 1 m or 10 degrees apart.
bool DistinctPoses(const Pose3& a, const Pose3& b) {
  constexpr double kDistinctM = 1.0, kDistinctRad = 10.0 * M_PI / 180.0;
  return (a.t - b.t).norm() > kDistinctM || so3::Log(a.R.transpose() * b.R).norm() > kDistinctRad;
}

// Best fit first.
void SortByFit(std::vector<ReferenceAlignment>* candidates) {
  std::stable_sort(candidates->begin(), candidates->end(),
                   [](const ReferenceAlignment& a, const ReferenceAlignment& b) {
                     return a.fit > b.fit;
                   });
}

}  // namespace

std::vector<ReferenceAlignment> SearchReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                                const Pose3& T_imu_lidar,
                                                const VoxelMap& reference,
                                                const Eigen::Matrix3d& R_start,
                                                const ConstraintOptions& constraints,
                                                const LocalizationOptions& options,
                                                const Eigen::Vector3d* around) {
  constexpr size_t kScorePoints = 256;
  const std::vector<Eigen::Vector3d> sample = Subsample(p_lidar, kScorePoints);
  const std::vector<Eigen::Vector3d> positions =
      around != nullptr ? PositionsAround(*around, options)
                        : FreeCellsNearSurfaces(OccupiedCells(reference, options.search_step),
                                                options.search_step);
  const int yaws = std::max(1, static_cast<int>(std::lround(360.0 / options.search_yaw_step)));
  std::vector<std::pair<double, Pose3>> scored;
  scored.reserve(positions.size() * yaws);
  const ConstraintOptions stage = StageOptions(constraints, options.align_radius_max);
  for (const Eigen::Vector3d& p : positions)
    for (int i = 0; i < yaws; ++i) {
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(2.0 * M_PI * i / yaws, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
          R_start;
      const Pose3 T(R, p);
      scored.emplace_back(OverlapWith(sample, T, T_imu_lidar, reference, stage), T);
    }
  // The best scored poses, one per place: a pose within the alignment's reach
  // of a better one kept (DistinctPoses) would align to the same place.
  std::stable_sort(scored.begin(), scored.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Pose3> kept;
  for (size_t i = 0; i < scored.size() && static_cast<int>(kept.size()) < options.search_keep; ++i)
    if (std::all_of(kept.begin(), kept.end(),
                    [&](const Pose3& k) { return DistinctPoses(k, scored[i].second); }))
      kept.push_back(scored[i].second);
  std::vector<ReferenceAlignment> aligned;
  for (const Pose3& T : kept)
    aligned.push_back(AlignToReference(p_lidar, T_imu_lidar, reference, T, constraints, options));
  SortByFit(&aligned);
  return aligned;
}

std::shared_ptr<const VoxelMap> MakeReferenceMap(const std::vector<Eigen::Vector3d>& p_ref,
                                                 const LocalizationOptions& options) {
  MapOptions o;  // the working map's thinning
  o.voxel_size = options.reference_voxel_size;
  o.neighbor_search = options.reference_neighbor_search;
  auto map = std::make_shared<VoxelMap>(o);
  map->Insert(p_ref);
  return map;
}

double ReferenceOverlap(const std::vector<Eigen::Vector3d>& p_lidar, const Pose3& T_ref_imu,
                        const Pose3& T_imu_lidar, const VoxelMap& reference,
                        const ConstraintOptions& constraints) {
  return OverlapWith(p_lidar, T_ref_imu, T_imu_lidar, reference, constraints);
}

ReferenceAlignment AlignToReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                    const Pose3& T_imu_lidar, const VoxelMap& reference,
                                    const Pose3& T_ref_imu_guess,
                                    const ConstraintOptions& constraints,
                                    const LocalizationOptions& options) {
  ReferenceAlignment a;
  a.T_ref_imu = T_ref_imu_guess;
  ConstraintList list;
  for (double radius = options.align_radius_max;; radius = std::max(0.5 * radius, options.align_radius_min)) {
    const ConstraintOptions stage = StageOptions(constraints, radius);
    for (int i = 0; i < options.align_iterations; ++i)
      if (!GaussNewtonStep(p_lidar, T_imu_lidar, reference, stage, radius, &list, &a.T_ref_imu))
        break;
    if (radius <= options.align_radius_min) break;
  }
  AssociateWith(p_lidar, a.T_ref_imu * T_imu_lidar, reference,
                StageOptions(constraints, options.align_radius_min), &list, nullptr);
  Vector6 b;
  Accumulate(list, a.T_ref_imu, T_imu_lidar, false, &a.information, &b);
  a.information /= constraints.lidar_noise * constraints.lidar_noise;
  WeakestAxis(a.information, constraints.lidar_noise, &a);
  a.constraints = static_cast<int>(list.size());
  a.overlap = ReferenceOverlap(p_lidar, a.T_ref_imu, T_imu_lidar, reference, constraints);
  ConstraintOptions tight = constraints;
  tight.max_residual = std::min(constraints.max_residual, kStartFitNoises * constraints.lidar_noise);
  a.fit = ReferenceOverlap(p_lidar, a.T_ref_imu, T_imu_lidar, reference, tight);
  return a;
}

namespace {

std::string Vec(const Eigen::Vector3d& v, int digits) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.*f, %.*f, %.*f)", digits, v.x(), digits, v.y(), digits,
                v.z());
  return text;
}

// "(x, y, z) yaw Y deg, N % of the points on their planes", the position in
// the map's frame as the user gave it.
std::string Describe(const ReferenceAlignment& a, const LocalOrigin& origin) {
  const Eigen::Vector3d x = a.T_ref_imu.R.col(0);
  char text[96];
  std::snprintf(text, sizeof(text), " yaw %.0f deg, %.0f %% of the points on their planes",
                std::atan2(x.y(), x.x()) * 180.0 / M_PI, 100.0 * a.fit);
  return Vec(origin.ToUser(a.T_ref_imu.t), 2) + text;
}

bool Distinct(const ReferenceAlignment& a, const ReferenceAlignment& b) {
  return DistinctPoses(a.T_ref_imu, b.T_ref_imu);
}

// A candidate distinct from `start` whose fit is within search_ambiguity of
// it or better, the best first (candidates sorted by fit), or null.
const ReferenceAlignment* RivalOf(const ReferenceAlignment& start,
                                  const std::vector<ReferenceAlignment>& candidates,
                                  double ambiguity) {
  for (const ReferenceAlignment& c : candidates) {
    if (c.fit < start.fit - ambiguity) break;
    if (Distinct(c, start)) return &c;
  }
  return nullptr;
}

std::string Percent(double share) {
  return std::to_string(static_cast<int>(std::lround(100.0 * share))) + " %";
}

Status TooLittleOverlap(const ReferenceAlignment& a, const LocalizationOptions& options,
                        const std::string& start_name) {
  return Status::InvalidInput(
      "the first scan does not match the reference map at " + start_name + " (" +
      Percent(a.overlap) + " of its points on reference planes after alignment, "
      "localization.min_start_overlap " + std::to_string(options.min_start_overlap) +
      "): check " + start_name + " and that the map is in the same frame and in metres");
}

Status Unfixed(const ReferenceAlignment& a, const LocalizationOptions& options, bool guided,
               const std::string& start_name) {
  char text[160];
  std::snprintf(text, sizeof(text), " (as %.1f constraints along it, "
                "localization.min_start_axis_constraints %g): featureless there",
                a.weakest_axis_constraints, options.min_start_axis_constraints);
  return Status::InvalidInput(
      "the first scan does not fix the start along " + Vec(a.weakest_axis, 2) +
      " in the reference" + text +
      (guided ? ", so " + start_name + " cannot be checked along it; start where the map has "
                "features, or set localization.trust_initial_pose=true"
              : "; give " + start_name));
}

// The map: even the best place fits the scan as no scan of the place fits
// its map.
Status MapDoesNotFit(const ReferenceAlignment& best, const LocalizationOptions& options,
                     bool guided, const std::string& start_name, const LocalOrigin& origin) {
  return Status::InvalidInput(
      "the first scan fits the reference map " +
      (guided ? "nowhere near " + start_name : std::string("nowhere the global search looked")) +
      " as a scan of the mapped place would: at best " + Percent(best.Consistency()) +
      " of its matched points lie on their reference planes (at " + Vec(origin.ToUser(best.T_ref_imu.t), 2) +
      "), localization.min_start_fit " + Percent(options.min_start_fit) +
      ": check that the map is of this place" +
      (guided ? " (and " + start_name + ")" : ", or give " + start_name));
}

}  // namespace

StatusOr<ReferenceAlignment> FindStartInReference(const std::vector<Eigen::Vector3d>& p_lidar,
                                                  const Pose3& T_imu_lidar,
                                                  const VoxelMap& reference,
                                                  const Pose3* T_ref_imu_guess,
                                                  const Eigen::Matrix3d& R_tilt,
                                                  const ConstraintOptions& constraints,
                                                  const LocalizationOptions& options,
                                                  const std::string& start_name,
                                                  const LocalOrigin& origin) {
  const bool guided = T_ref_imu_guess != nullptr;
  std::vector<ReferenceAlignment> candidates;
  if (!guided || (!options.trust_initial_pose && options.start_check_radius > 0.0))
    candidates = SearchReference(p_lidar, T_imu_lidar, reference,
                                 guided ? T_ref_imu_guess->R : R_tilt, constraints, options,
                                 guided ? &T_ref_imu_guess->t : nullptr);
  if (!guided && (candidates.empty() || !(candidates.front().overlap >= options.min_start_overlap)))
    return Status::InvalidInput(
        "no place in the reference map matches the first scan (global search); check that the "
        "map is in metres and covers the start, or give " + start_name);
  const ReferenceAlignment start =
      guided ? AlignToReference(p_lidar, T_imu_lidar, reference, *T_ref_imu_guess, constraints,
                                options)
             : candidates.front();
  if (!(start.overlap >= options.min_start_overlap))
    return TooLittleOverlap(start, options, start_name);
  if (start.weakest_axis_constraints < options.min_start_axis_constraints &&
      !(guided && options.trust_initial_pose))
    return Unfixed(start, options, guided, start_name);
  candidates.push_back(start);
  SortByFit(&candidates);
  const ReferenceAlignment& best = candidates.front();
  if (!(best.Consistency() >= options.min_start_fit))
    return MapDoesNotFit(best, options, guided, start_name, origin);
  const ReferenceAlignment* rival = RivalOf(start, candidates, options.search_ambiguity);
  if (rival == nullptr) return start;
  if (!guided)
    return Status::InvalidInput("the first scan matches the reference map equally well at " +
                                Describe(start, origin) + " and at " + Describe(*rival, origin) +
                                " (global search): give " + start_name);
  if (rival->fit > start.fit + options.search_ambiguity)
    return Status::InvalidInput(
        "the first scan fits the reference map better at " + Describe(*rival, origin) +
        " than at " + start_name + " (aligned to " + Describe(start, origin) + "): " + start_name +
        " is wrong there");
  return Status::InvalidInput(
      "the first scan fits the reference map as well at " + Describe(*rival, origin) + " as at " +
      start_name + " (aligned to " + Describe(start, origin) + "), within localization.search_ambiguity " +
      std::to_string(options.search_ambiguity) + ": the start is ambiguous there; start where "
      "the map has features, or set localization.trust_initial_pose=true");
}

}  // namespace rvlio
