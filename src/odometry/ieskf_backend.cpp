#include "rvlio/odometry/ieskf_backend.h"

#include <utility>

#include "rvlio/common/parallel.h"
#include "rvlio/constraints/plane_association.h"
#include "rvlio/lidar/extrinsics.h"

namespace rvlio {

IeskfBackend::IeskfBackend(const OdometryOptions& options)
    : options_(options),
      filter_(options.ieskf, options.imu, options.constraints, options.rv, options.lidar,
              options.degeneracy) {}

void IeskfBackend::Initialize(const StaticAlignment& a, const ImuSample& imu,
                              std::deque<ImuSample>*) {
  const Pose3 T_imu_lidar = ImuTLidar(options_.extrinsics);
  FilterState x0;
  x0.R_world_imu = a.R_world_imu;
  x0.g_world = a.g_world;
  x0.bg = a.gyro_bias;
  x0.R_imu_lidar = T_imu_lidar.R;
  x0.t_imu_lidar = T_imu_lidar.t;
  filter_.Initialize(x0, imu.t_ns, imu);
}

// The pose history starts at the state after the last scan (or the skipped
// one's prediction), so it holds exactly this scan's propagation.
Prediction IeskfBackend::Predict(std::deque<ImuSample>* imu_buffer, TimeNs t_end_ns) {
  filter_.ClearPoseHistory();
  Prediction p;
  p.mean_imu.t_ns = t_end_ns;
  int n = 0;
  while (!imu_buffer->empty() && imu_buffer->front().t_ns <= t_end_ns) {
    filter_.Propagate(imu_buffer->front());
    p.mean_imu.acc_imu += imu_buffer->front().acc_imu;
    p.mean_imu.gyro_imu += imu_buffer->front().gyro_imu;
    ++n;
    imu_buffer->pop_front();
  }
  filter_.PropagateTo(t_end_ns);
  if (n > 0) {
    p.mean_imu.acc_imu /= n;
    p.mean_imu.gyro_imu /= n;
  }
  const FilterState& x = filter_.state();
  p.at_end.t_ns = filter_.time_ns();
  p.at_end.R_world_imu = x.R_world_imu;
  p.at_end.p_world_imu = x.p_world_imu;
  p.at_end.v_world_imu = x.v_world_imu;
  p.poses = &filter_.pose_history();
  return p;
}

// The filter's rotation error is a right perturbation (R = R_hat Exp(d));
// about the world axes it is R_hat d, so the covariance's rotation rows turn
// by R_hat.
void IeskfBackend::ReportPropagationState(ScanResult* r) const {
  const FilterState& x = filter_.state();
  r->bg_imu = x.bg;
  r->ba_imu = x.ba;
  r->g_world = x.g_world;
  Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
  J.block<3, 3>(0, FilterState::kPos) = Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, FilterState::kRot) = x.R_world_imu;
  const Eigen::Matrix<double, 6, 6> P = filter_.covariance().topLeftCorner<6, 6>();
  r->pose_covariance_world = J * P * J.transpose();
}

void IeskfBackend::ChangeWorldFrame(const Pose3& T_ref_world, Prediction* prediction) {
  filter_.ChangeWorldFrame(T_ref_world);
  const FilterState& x = filter_.state();
  prediction->at_end.R_world_imu = x.R_world_imu;
  prediction->at_end.p_world_imu = x.p_world_imu;
  prediction->at_end.v_world_imu = x.v_world_imu;
}

ScanStatus IeskfBackend::Update(ScanContext& scan, ScanResult* r) {
  if (scan.map->Empty() && !scan.localizer->enabled()) return ScanStatus::kMapInit;
  return Correct(scan, r);
}

// The iterations of one scan share an AssociationCache: a point whose world
// position moved less than constraints.reuse_distance since its last k-NN
// search keeps that plane (with a fresh residual), so the later iterations,
// which move the pose by millimetres, mostly skip the search (the dominant
// cost, bench/RESULTS.md). A new cache per scan: the map changed since.
// With a reference map, the scan is matched with the reference, or with the
// working map when it overlaps the reference too little at the prediction
// (ReferenceLocalizer::Associate; its search fills the cache, which the
// first iteration then reuses).
ScanStatus IeskfBackend::Correct(ScanContext& scan, ScanResult* r) {
  const int threads = ResolveThreads(options_.constraints.threads);
  const std::vector<Eigen::Vector3d>& p_lidar = *scan.p_lidar;
  AssociationCache cache(options_.constraints.reuse_distance);
  const FilterState& predicted = filter_.state();
  const VoxelMap& search =
      scan.localizer->enabled()
          ? scan.localizer->Associate(p_lidar, predicted.T_world_imu(), predicted.T_imu_lidar(),
                                      scan.map->map(), &cache, threads, &choice_, r)
          : scan.map->map();
  const AssociateFn associate = [this, &p_lidar, &cache, &search, threads](
                                    const FilterState& x, ConstraintList* constraints) {
    AssociationStats stats;
    Associate(p_lidar, x.T_world_imu(), x.T_imu_lidar(), search, options_.constraints,
              constraints, &stats, &cache, threads);
  };
  const IeskfUpdateResult u = filter_.Update(associate);
  r->constraints = u.num_constraints;
  r->iterations = u.iterations;
  r->rv = u.rv;
  r->degeneracy = u.degeneracy;
  r->health.nis_per_dof = u.nis_per_dof;
  r->health.lidar_rotation_imu = u.lidar_rotation_imu;
  if (u.ok) {
    r->health.residual_median_m = u.residuals.median_abs_m;
    r->health.residual_rms_m = u.residuals.rms_m;
  }
  if (u.diverged) {
    ++scan.stats->diverged_resets;
    return ScanStatus::kDiverged;
  }
  if (!u.ok) {
    ++scan.stats->predict_only;
    return ScanStatus::kPredictOnly;
  }
  return ScanStatus::kUpdated;
}

// The scan's points were deskewed to its end on the LiDAR clock, which the
// estimated offset puts at the filter's ScanTimeImuPose().
void IeskfBackend::Insert(ScanContext& scan) {
  const bool provisional = ProvisionalInMap(scan.t_ns, scan.map);
  const FilterState& x = filter_.state();
  const Pose3 T_world_imu =
      options_.lidar.estimate_time_offset ? filter_.ScanTimeImuPose() : x.T_world_imu();
  const std::vector<Eigen::Vector3d>& p_world =
      scan.map->InsertScan(scan.t_ns, T_world_imu, x.T_imu_lidar(), *scan.p_lidar);
  if (!provisional) scan.output->Insert(scan.t_ns, p_world);
}

// The map hold (lidar.time_offset_map_hold, docs/time_offset.md "Map hold"):
// the offset is not observed at rest, so the first moving scans are predicted,
// deskewed and placed with the prior offset, and the filter cannot revisit the
// map it builds from them. At the first moving scan the working map is copied
// (the scans at rest, which the offset does not affect); the moving scans are
// then inserted provisionally (registration keeps a fresh map) and kept out of
// the output map. When the offset's 1-sigma falls below
// lidar.time_offset_map_std, the working map returns to the copy, so the
// provisional scans, deskewed and placed with the unconverged offset, leave
// it, and the scans from then on rebuild it. If the offset does not converge
// within time_offset_map_hold seconds of motion, the provisional scans stay.
// Memory: one copy of the working map, once per run.
bool IeskfBackend::ProvisionalInMap(TimeNs t_ns, WorkingMap* map) {
  if (map_hold_over_ || !options_.lidar.estimate_time_offset ||
      options_.lidar.time_offset_map_hold <= 0.0 || map->Empty())
    return false;
  if (map_hold_start_ns_ < 0) {
    if (!filter_.time_offset_observed()) return false;  // at rest: the offset does not matter
    map_hold_start_ns_ = t_ns;
    map_before_motion_ = *map;
  }
  const bool converged = filter_.time_offset_std_s() < options_.lidar.time_offset_map_std;
  if (converged) *map = std::move(*map_before_motion_);
  map_hold_over_ =
      converged || NsToSeconds(t_ns - map_hold_start_ns_) >= options_.lidar.time_offset_map_hold;
  if (map_hold_over_) {
    map_before_motion_.reset();
    return false;
  }
  ++map_hold_scans_;
  return true;
}

}  // namespace rvlio
