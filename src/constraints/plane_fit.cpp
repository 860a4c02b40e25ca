#include "rvlio/constraints/plane_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

namespace rvlio {

namespace {

// Below this largest eigenvalue (m^2) the points coincide numerically.
constexpr double kDegenerateSpread = 1e-18;

// Centroid and covariance C = 1/n sum (p_i - c)(p_i - c)^T, accumulated
// relative to the first point so that precision does not depend on the
// distance from the world origin.
void CentroidAndCovariance(const Eigen::Vector3d* points, int n, Eigen::Vector3d* centroid,
                           Eigen::Matrix3d* covariance) {
  const Eigen::Vector3d origin = points[0];
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) mean += points[i] - origin;
  mean /= n;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = points[i] - origin - mean;
    C.noalias() += d * d.transpose();
  }
  *covariance = C / n;
  *centroid = origin + mean;
}

double MaxPlaneDistance(const Eigen::Vector3d* points, int n, const Eigen::Vector3d& normal,
                        const Eigen::Vector3d& centroid) {
  double max_distance = 0.0;
  for (int i = 0; i < n; ++i)
    max_distance = std::max(max_distance, std::abs(normal.dot(points[i] - centroid)));
  return max_distance;
}

// sqrt(sigma^2 / (n lambda_mid)), see the header.
double NormalStd(const Eigen::Vector3d& eigenvalues, int n, double point_noise) {
  double sigma2 = point_noise * point_noise;
  if (n > 3) sigma2 = std::max(sigma2, n * eigenvalues(0) / (n - 3));
  if (!(eigenvalues(1) > 0.0)) return std::numeric_limits<double>::infinity();
  return std::sqrt(sigma2 / (n * eigenvalues(1)));
}

PlaneStatus Classify(const LocalPlane& plane, const PlaneThresholds& t) {
  const double l_min = plane.eigenvalues(0);
  const double l_mid = plane.eigenvalues(1);
  const double l_max = plane.eigenvalues(2);
  if (!(l_max > kDegenerateSpread)) return PlaneStatus::kDegenerate;
  if (!(l_mid > 0.0) || l_mid < t.planarity_min_ratio * l_max) return PlaneStatus::kLineLike;
  if (l_min > t.planarity_max_ratio * l_mid) return PlaneStatus::kNotFlat;
  if (plane.max_distance > t.max_plane_distance) return PlaneStatus::kFarFromPlane;
  if (t.max_normal_std > 0.0 && plane.normal_std > t.max_normal_std) return PlaneStatus::kUncertain;
  return PlaneStatus::kValid;
}

}  // namespace

const char* ToString(PlaneStatus status) {
  switch (status) {
    case PlaneStatus::kValid: return "valid";
    case PlaneStatus::kTooFewPoints: return "too_few_points";
    case PlaneStatus::kDegenerate: return "degenerate";
    case PlaneStatus::kLineLike: return "line_like";
    case PlaneStatus::kNotFlat: return "not_flat";
    case PlaneStatus::kFarFromPlane: return "far_from_plane";
    case PlaneStatus::kUncertain: return "uncertain";
  }
  return "unknown";
}

LocalPlane FitLocalPlane(const Eigen::Vector3d* points, int n, const PlaneThresholds& thresholds) {
  LocalPlane plane;
  if (n < 3) {
    plane.status = PlaneStatus::kTooFewPoints;
    return plane;
  }
  Eigen::Matrix3d C;
  CentroidAndCovariance(points, n, &plane.centroid, &C);
  if (!C.allFinite() || !plane.centroid.allFinite()) {
    plane.status = PlaneStatus::kDegenerate;
    return plane;
  }
  // Closed-form 3x3 eigen-decomposition (eigenvalues ascending); the normal
  // is the eigenvector of the smallest eigenvalue.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(C);
  plane.eigenvalues = solver.eigenvalues().cwiseMax(0.0);
  plane.normal = solver.eigenvectors().col(0).normalized();
  plane.max_distance = MaxPlaneDistance(points, n, plane.normal, plane.centroid);
  plane.normal_std = NormalStd(plane.eigenvalues, n, thresholds.point_noise);
  plane.status = Classify(plane, thresholds);
  return plane;
}

}  // namespace rvlio
