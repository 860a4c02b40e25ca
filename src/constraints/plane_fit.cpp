#include "rvlio/constraints/plane_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

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

// Eigenvalues (ascending) of the symmetric covariance C and the unit
// eigenvector of the smallest, without trigonometry:
// * lambda_min: Newton on the characteristic polynomial
//   p(l) = l^3 - tr l^2 + c1 l - det from l = 0. Below the smallest root p is
//   negative, increasing and concave, so the iterates rise monotonically to
//   lambda_min (quadratically once near it; slowly only when lambda_min ~
//   lambda_mid, a neighbourhood the flatness test rejects anyway).
// * lambda_mid, lambda_max: roots of the remaining quadratic
//   l^2 - (tr - lambda_min) l + (c1 - lambda_min (tr - lambda_min)).
// * normal: the largest cross product of two rows of C - lambda_min I (the
//   rows span the plane orthogonal to the normal).
// Falls back to Eigen's closed-form solver when the rows are (near) parallel.
void SmallestEigen(const Eigen::Matrix3d& C, Eigen::Vector3d* eigenvalues,
                   Eigen::Vector3d* normal) {
  const double a = C(0, 0), b = C(1, 1), c = C(2, 2), d = C(0, 1), e = C(0, 2), f = C(1, 2);
  const double tr = a + b + c;
  const double c1 = a * b + a * c + b * c - d * d - e * e - f * f;
  const double det = a * (b * c - f * f) - d * (d * c - e * f) + e * (d * f - b * e);
  double l = 0.0;
  for (int it = 0; it < 32; ++it) {
    const double p = ((l - tr) * l + c1) * l - det;
    const double dp = (3.0 * l - 2.0 * tr) * l + c1;
    if (!(dp > 0.0)) break;
    const double step = p / dp;
    l -= step;
    if (!(std::abs(step) > 1e-15 * tr)) break;
  }
  const double rest = tr - l;
  const double prod = std::max(0.0, c1 - l * rest);
  const double l_max = 0.5 * (rest + std::sqrt(std::max(0.0, rest * rest - 4.0 * prod)));
  const double l_mid = l_max > 0.0 ? prod / l_max : 0.0;
  *eigenvalues = Eigen::Vector3d(std::max(0.0, l), l_mid, l_max);

  const Eigen::Vector3d r0(a - l, d, e), r1(d, b - l, f), r2(e, f, c - l);
  const Eigen::Vector3d x01 = r0.cross(r1), x02 = r0.cross(r2), x12 = r1.cross(r2);
  const double n01 = x01.squaredNorm(), n02 = x02.squaredNorm(), n12 = x12.squaredNorm();
  const Eigen::Vector3d& best = n01 >= n02 ? (n01 >= n12 ? x01 : x12) : (n02 >= n12 ? x02 : x12);
  const double best_n = std::max({n01, n02, n12});
  // |x|^2 ~ (lambda_mid lambda_max)^2 for a well-separated smallest root.
  if (std::isfinite(best_n) && best_n > 1e-20 * tr * tr * tr * tr) {
    *normal = best / std::sqrt(best_n);
    return;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(C);
  *eigenvalues = solver.eigenvalues().cwiseMax(0.0);
  *normal = solver.eigenvectors().col(0).normalized();
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
    case PlaneStatus::kValid:
      return "valid";
    case PlaneStatus::kTooFewPoints:
      return "too_few_points";
    case PlaneStatus::kDegenerate:
      return "degenerate";
    case PlaneStatus::kLineLike:
      return "line_like";
    case PlaneStatus::kNotFlat:
      return "not_flat";
    case PlaneStatus::kFarFromPlane:
      return "far_from_plane";
    case PlaneStatus::kUncertain:
      return "uncertain";
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
  SmallestEigen(C, &plane.eigenvalues, &plane.normal);
  plane.max_distance = MaxPlaneDistance(points, n, plane.normal, plane.centroid);
  plane.normal_std = NormalStd(plane.eigenvalues, n, thresholds.point_noise);
  plane.status = Classify(plane, thresholds);
  return plane;
}

}  // namespace rvlio
