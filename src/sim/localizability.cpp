#include "rvlio/sim/localizability.h"

#include <Eigen/Eigenvalues>

namespace rvlio::sim {

namespace {

// The estimator's preprocessing with the simulated sensor's crop.
LidarOptions GridOptions(const SimLocalizabilityOptions& options, const SimLidarOptions& lidar) {
  LidarOptions o;
  o.min_range = lidar.min_range;
  o.max_range = lidar.max_range;
  o.voxel_size = options.voxel_size;
  return o;
}

// Flips v so that its component of largest magnitude is positive.
template <class Vec>
Vec Signed(Vec v) {
  int largest = 0;
  v.cwiseAbs().maxCoeff(&largest);
  return v(largest) < 0.0 ? Vec(-v) : v;
}

}  // namespace

ScanLocalizability LocalizabilityOf(const std::vector<SurfaceHit>& hits,
                                    const std::vector<int>& indices, double degenerate_ratio) {
  ScanLocalizability out;
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i : indices) {
    const SurfaceHit& h = hits[static_cast<size_t>(i)];
    if (h.normal_world.squaredNorm() == 0.0) continue;
    Vector6d J;
    J << (h.p_world - h.origin_world).cross(h.normal_world), h.normal_world;
    H.noalias() += J * J.transpose();
    ++out.points;
  }
  if (out.points == 0) return out;
  H /= out.points;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> translation(H.bottomRightCorner<3, 3>());
  out.eigenvalues = translation.eigenvalues();
  out.weak_dir_world = Signed(Eigen::Vector3d(translation.eigenvectors().col(0).normalized()));
  out.ratio = out.eigenvalues[2] > 0.0 ? out.eigenvalues[0] / out.eigenvalues[2] : 0.0;
  out.degenerate = out.ratio < degenerate_ratio;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> pose(H);
  out.pose_eigenvalue_min = pose.eigenvalues()[0];
  out.pose_weak = Signed(Vector6d(pose.eigenvectors().col(0).normalized()));
  return out;
}

LocalizabilityTruth::LocalizabilityTruth(const SimLocalizabilityOptions& options,
                                         const SimLidarOptions& lidar)
    : degenerate_ratio_(options.degenerate_ratio), preprocessor_(GridOptions(options, lidar)) {}

ScanLocalizability LocalizabilityTruth::Compute(const World& world, const Scan& scan,
                                                std::vector<SurfaceHit>* hits) {
  preprocessor_.SelectIndices(scan, &kept_);
  for (int i : kept_) {
    SurfaceHit& h = (*hits)[static_cast<size_t>(i)];
    if (h.returned) h.normal_world = world.Normal(h.surface, h.p_world);
  }
  ScanLocalizability out = LocalizabilityOf(*hits, kept_, degenerate_ratio_);
  out.t_ns = scan.t_end_ns;
  return out;
}

}  // namespace rvlio::sim
