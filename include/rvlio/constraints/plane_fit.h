#pragma once
// Local plane fit of a scan point's map neighbours, with the validity test of
// docs/design.md "The shared measurement model".
//
// The plane is the total-least-squares fit: centroid c of the n points and the
// eigen-decomposition of their covariance C = 1/n sum (p_i - c)(p_i - c)^T with
// eigenvalues lambda_min <= lambda_mid <= lambda_max; the unit normal u is the
// eigenvector of lambda_min. On noise-free coplanar points this is the same
// plane as the paper's least-squares form a x + b y + c z + 1 = 0 (then
// (a, b, c) = -u / (u . c), see PaperCoefficients), but it does not depend on
// where the world origin is and stays defined for planes through it.
//
// Validity (a line admits any plane through it, so the distance test alone
// would accept an essentially random normal on a 32-beam ring line):
//   line-like : lambda_mid < planarity_min_ratio * lambda_max   (ring line, edge)
//   not flat  : lambda_min > planarity_max_ratio * lambda_mid   (corner, clutter)
//   far point : some |u . (p_i - c)| > max_plane_distance
//   uncertain : the normal's predicted tilt std exceeds max_normal_std
//
// The last test is what keeps noisy near-lines out: points with in-plane
// covariance eigenvalues lambda_max, lambda_mid and noise sigma along the
// normal determine the normal's tilt towards the mid axis with variance
// sigma^2 / (n lambda_mid) (the slope variance of a line regression), so
//   normal_std = sqrt(sigma^2 / (n lambda_mid)),
//   sigma^2    = max(point_noise^2, n lambda_min / (n - 3))
// (the configured sensor noise, or the fit's own residual variance when that
// is larger). A ring line has lambda_mid ~ 0 and an arbitrary normal; a small
// patch of noisy points has a poorly determined one. Both are rejected.
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "rvlio/constraints/options.h"
#include "rvlio/map/voxel_map.h"

namespace rvlio {

enum class PlaneStatus : uint8_t {
  kValid = 0,
  kTooFewPoints,  // fewer than 3 points
  kDegenerate,    // all points (numerically) coincide or are non-finite
  kLineLike,      // lambda_mid / lambda_max below planarity_min_ratio
  kNotFlat,       // lambda_min / lambda_mid above planarity_max_ratio
  kFarFromPlane,  // a point farther than max_plane_distance from the plane
  kUncertain,     // normal's predicted tilt std above max_normal_std
};

const char* ToString(PlaneStatus status);

struct LocalPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();      // unit normal u (sign arbitrary)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();     // point q on the plane, m
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  // covariance, ascending, m^2
  double max_distance = 0.0;  // largest |u . (p_i - q)| over the points, m
  double normal_std = 0.0;    // predicted 1-sigma tilt of the normal, rad
  PlaneStatus status = PlaneStatus::kTooFewPoints;

  bool valid() const { return status == PlaneStatus::kValid; }
  // Paper form (a, b, c) with a x + b y + c z + 1 = 0; infinite when the plane
  // passes through the origin.
  Eigen::Vector3d PaperCoefficients() const { return -normal / normal.dot(centroid); }
};

// Thresholds of the validity test (the plane fields of ConstraintOptions).
struct PlaneThresholds {
  double planarity_min_ratio = 0.1;
  double planarity_max_ratio = 0.1;
  double max_plane_distance = 0.1;  // m
  double max_normal_std = 0.0;      // rad, 0: test off
  double point_noise = 0.03;        // m, std of a map point along the normal

  static PlaneThresholds From(const ConstraintOptions& o) {
    return PlaneThresholds{o.planarity_min_ratio, o.planarity_max_ratio, o.max_plane_distance,
                           o.max_normal_std_deg * M_PI / 180.0, o.lidar_noise};
  }
};

// Fits and validates a plane through points[0..n). No heap allocation.
LocalPlane FitLocalPlane(const Eigen::Vector3d* points, int n, const PlaneThresholds& thresholds);

inline LocalPlane FitLocalPlane(const std::vector<Eigen::Vector3d>& points,
                                const PlaneThresholds& thresholds) {
  return FitLocalPlane(points.data(), static_cast<int>(points.size()), thresholds);
}
inline LocalPlane FitLocalPlane(const NeighborBuffer& neighbors,
                                const PlaneThresholds& thresholds) {
  return FitLocalPlane(neighbors.points.data(), neighbors.size, thresholds);
}

}  // namespace rvlio
