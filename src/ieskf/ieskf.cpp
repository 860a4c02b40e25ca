#include "rvlio/ieskf/ieskf.h"

#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

#include "rvlio/common/check.h"
#include "rvlio/constraints/point_to_plane.h"
#include "rvlio/math/so3.h"
#include "state_policies.h"

namespace rvlio {
namespace {

using Matrix24x12d = Eigen::Matrix<double, 24, 12>;

// Fixed extrinsics: a tiny std keeps P invertible; no update touches the block.
constexpr double kFixedExtrinsicStd = 1e-5;  // rad and m

Vector6d ExtrinsicPriorStd(const IeskfOptions& o) {
  Vector6d sd;
  sd << Eigen::Vector3d::Constant(o.init_extrinsic_rot_std),
      Eigen::Vector3d::Constant(o.init_extrinsic_pos_std);
  return sd;
}

// Prior covariance from the configured standard deviations.
Matrix24d InitialCovariance(const IeskfOptions& o) {
  Vector24d sd;
  sd.segment<3>(FilterState::kRot).setConstant(o.init_rot_std);
  sd.segment<3>(FilterState::kPos).setConstant(o.init_pos_std);
  sd.segment<3>(FilterState::kVel).setConstant(o.init_vel_std);
  sd.segment<3>(FilterState::kBg).setConstant(o.init_bias_gyro_std);
  sd.segment<3>(FilterState::kBa).setConstant(o.init_bias_acc_std);
  // Estimated extrinsics start held too: an axis gets its prior std once the
  // motion excites it (Ieskf::ReleaseExcitedAxes).
  sd.segment<6>(FilterState::kExtRot).setConstant(kFixedExtrinsicStd);
  sd.segment<3>(FilterState::kGrav).setConstant(o.init_gravity_std);
  return sd.cwiseAbs2().asDiagonal();
}

bool IsHealthy(const FilterState& x, const Matrix24d& P) {
  if (!x.R_world_imu.allFinite() || !x.p_world_imu.allFinite() || !x.v_world_imu.allFinite() ||
      !x.bg.allFinite() || !x.ba.allFinite() || !x.g_world.allFinite() || !P.allFinite())
    return false;
  // Exploding covariance: a position std of kilometres means the filter lost it.
  return P.diagonal().maxCoeff() < 1e6 && P.diagonal().minCoeff() > -1e-9;
}

void PropagateCovariance(const Matrix24d& F, const ImuOptions& imu, double dt_s, Matrix24d* P) {
  *P = F * *P * F.transpose();
  auto add_diag = [&](int index, double variance) {
    for (int i = 0; i < 3; ++i) (*P)(index + i, index + i) += variance;
  };
  add_diag(FilterState::kRot, imu.gyro_noise_density * imu.gyro_noise_density * dt_s);
  add_diag(FilterState::kVel, imu.accel_noise_density * imu.accel_noise_density * dt_s);
  add_diag(FilterState::kBg, imu.gyro_bias_random_walk * imu.gyro_bias_random_walk * dt_s);
  add_diag(FilterState::kBa, imu.accel_bias_random_walk * imu.accel_bias_random_walk * dt_s);
}

// The covariance the excitation monitor starts from: P0 with an uninformative
// initial pose. The map is built from the first scans with the configured
// extrinsic, so the start pose of the map frame carries no information on the
// extrinsic; with the tight P0 pose block, the map (taken as exact by the
// update) would make the extrinsic look determined by any scan. Loose, only
// the relative motion (IMU) against the LiDAR's (map) informs it: the
// hand-eye condition, which needs rotation.
constexpr double kGaugeFreePoseStd = 1.0;  // rad and m

Matrix24d ExcitationCovariance(const Matrix24d& P0, const Vector6d& extrinsic_std) {
  Matrix24d P = P0;
  for (int i = 0; i < 6; ++i) {
    P(FilterState::kRot + i, FilterState::kRot + i) = kGaugeFreePoseStd * kGaugeFreePoseStd;
    P(FilterState::kExtRot + i, FilterState::kExtRot + i) = extrinsic_std(i) * extrinsic_std(i);
  }
  return P;
}

// The rotation step of the point-to-plane normal equations alone (columns
// [dtheta, dp, ...]: the first three), position held (rad, IMU frame); NaN
// when the rotation is not observable from them.
template <class MatrixC, class VectorC>
Eigen::Vector3d LidarOnlyRotation(const MatrixC& HtRinvH, const VectorC& HtRinvz) {
  const Eigen::Vector3d unknown = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  const Eigen::Matrix3d H_rr = HtRinvH.template topLeftCorner<3, 3>();
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(H_rr);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return unknown;
  const Eigen::Vector3d dtheta = -ldlt.solve(HtRinvz.template head<3>());
  return dtheta.allFinite() ? dtheta : unknown;
}

// The degeneracy stage of one iteration on the pose block of the normal
// equations (sigma = 1 information); rv and none report from the RV pass.
template <class MatrixC>
DegeneracyTreatment AnalyzeScanDegeneracy(const DegeneracyOptions& options, const RvReport& rv,
                                          const MatrixC& HtRinvH, double inv_sigma2,
                                          const ConstraintList& constraints,
                                          const FilterState& x_scan) {
  const PoseMatrix6d H_pose = HtRinvH.template topLeftCorner<6, 6>() / inv_sigma2;
  if (options.method == DegeneracyMethod::kRv || options.method == DegeneracyMethod::kNone) {
    DegeneracyTreatment t;
    t.report = DegeneracyReportFromRv(options.method, rv, H_pose.block<3, 3>(3, 3));
    return t;
  }
  return AnalyzeDegeneracy(options, H_pose, constraints, x_scan.T_world_imu(), x_scan.T_imu_lidar());
}

// remap: the increment without its degenerate components; localizability:
// the update solved with the held directions fixed; regularized: solved with
// the damping added along the weak directions. The pose is dx's first six
// entries (FilterState::kRot, kPos).
template <class MatrixN, class VectorN>
void TreatIncrement(DegeneracyMethod method, const DegeneracyTreatment& t, double inv_sigma2,
                    const MatrixN& A, const VectorN& b, VectorN* dx) {
  static_assert(FilterState::kRot == 0 && FilterState::kPos == 3, "pose block first");
  switch (method) {
    case DegeneracyMethod::kRemap:
      ProjectOutHeld(t, dx->template head<6>());
      break;
    case DegeneracyMethod::kLocalizability:
      if (t.num_held > 0) *dx = SolveHoldingDirections(t, A, b);
      break;
    case DegeneracyMethod::kRegularized:
      if (t.report.num_damped > 0) {
        MatrixN A_damped = A;
        A_damped.template topLeftCorner<6, 6>() += t.damping * inv_sigma2;
        *dx = -A_damped.ldlt().solve(b);
      }
      break;
    case DegeneracyMethod::kRv:
    case DegeneracyMethod::kNone:
      break;
  }
}

}  // namespace

// The extrinsic block is not adjacent to the pose block in the error state
// (FilterState offsets), so the columns are placed one by one.
Matrix24x12d ErrorStateColumns(const std::array<bool, 6>& free) {
  Matrix24x12d E = Matrix24x12d::Zero();
  E.block<6, 6>(FilterState::kRot, 0).setIdentity();  // kRot, kPos adjacent
  for (int i = 0; i < 6; ++i)
    if (free[i]) E(FilterState::kExtRot + i, 6 + i) = 1.0;  // kExtRot, kExtPos adjacent
  return E;
}

Ieskf::Ieskf(const IeskfOptions& options, const ImuOptions& imu,
             const ConstraintOptions& constraints, const RvOptions& rv, const LidarOptions& lidar,
             const DegeneracyOptions& degeneracy)
    : options_(options),
      imu_(imu),
      constraints_(constraints),
      rv_(EffectiveRvOptions(rv, degeneracy)),
      degeneracy_(degeneracy),
      lidar_(lidar),
      state_kind_(lidar.estimate_time_offset ? KindOf<TimeOffsetState>()
                                             : KindOf<NoTimeOffsetState>()) {}

template <class StatePolicy>
Ieskf::StateKind Ieskf::KindOf() {
  return {&StatePolicy::Start, &StatePolicy::Propagate, &Ieskf::UpdateImpl<StatePolicy>};
}

void Ieskf::Initialize(const FilterState& x0, TimeNs t_ns, const ImuSample& last_imu) {
  x_ = x0;
  P_ = InitialCovariance(options_);
  P_all_extrinsic_ = ExcitationCovariance(P_, ExtrinsicPriorStd(options_));
  released_.fill(false);
  excitation_ = ExtrinsicExcitation(ExtrinsicPriorStd(options_));
  t_ns_ = t_ns;
  last_imu_ = last_imu;
  state_kind_.start(lidar_, &td_);
  ClearPoseHistory();
}

double Ieskf::time_offset_std_s() const { return std::sqrt(std::max(td_.P_td_td, 0.0)); }

void Ieskf::SetTimeOffset(double td_s, double std_s) {
  td_.td_s = td_.td_lin_s = td_s;
  td_.P_x_td.setZero();
  td_.P_td_td = std_s * std_s;
}

// A copy of the filter is propagated as Predict would: the state Update
// would judge the offset's observability on.
bool Ieskf::TimeOffsetObservableAt(const std::deque<ImuSample>& imu, TimeNs t_end_ns) const {
  Ieskf probe = *this;
  probe.ClearPoseHistory();
  for (const ImuSample& s : imu) {
    if (s.t_ns > t_end_ns) break;
    probe.Propagate(s);
  }
  probe.PropagateTo(t_end_ns);
  return TimeOffsetObservable(probe.x_.v_world_imu, probe.MotionAtStateTime());
}
void Ieskf::ChangeWorldFrame(const Pose3& T_new_old) {
  x_.R_world_imu = T_new_old.R * x_.R_world_imu;
  x_.p_world_imu = T_new_old * x_.p_world_imu;
  x_.v_world_imu = T_new_old.R * x_.v_world_imu;
  x_.g_world = T_new_old.R * x_.g_world;
  Matrix24d J = Matrix24d::Identity();
  for (int k : {FilterState::kPos, FilterState::kVel, FilterState::kGrav})
    J.block<3, 3>(k, k) = T_new_old.R;
  P_ = J * P_ * J.transpose();
  P_all_extrinsic_ = J * P_all_extrinsic_ * J.transpose();
  ClearPoseHistory();
}

void Ieskf::ClearPoseHistory() {
  pose_history_.Clear();
  RecordPose(last_imu_.gyro_imu, last_imu_.acc_imu);
}

void Ieskf::RecordPose(const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& acc_imu) {
  ImuPoseSample s;
  s.t_ns = t_ns_;
  s.R_world_imu = x_.R_world_imu;
  s.p_world_imu = x_.p_world_imu;
  s.v_world_imu = x_.v_world_imu;
  s.gyro_imu = gyro_imu - x_.bg;
  s.acc_world = x_.R_world_imu * (acc_imu - x_.ba) + x_.g_world;
  pose_history_.Append(s);
}

void Ieskf::Propagate(const ImuSample& imu) {
  if (imu.t_ns > t_ns_) {
    const double dt_s = NsToSeconds(imu.t_ns - t_ns_);
    Step(0.5 * (last_imu_.gyro_imu + imu.gyro_imu), 0.5 * (last_imu_.acc_imu + imu.acc_imu), dt_s);
    t_ns_ = imu.t_ns;
  }
  last_imu_ = imu;
  RecordPose(imu.gyro_imu, imu.acc_imu);
}

void Ieskf::PropagateTo(TimeNs t_ns) {
  if (t_ns <= t_ns_) return;
  Step(last_imu_.gyro_imu, last_imu_.acc_imu, NsToSeconds(t_ns - t_ns_));
  t_ns_ = t_ns;
  RecordPose(last_imu_.gyro_imu, last_imu_.acc_imu);
}

// Mean and error-state propagation over dt with constant (bias-corrected)
// rate w and specific force a, right perturbation on R:
//   R+ = R Exp(w dt),  v+ = v + (Rm a + g) dt,  p+ = p + v dt + 1/2 (Rm a + g) dt^2
//   with Rm = R Exp(w dt / 2),
//   dtheta+ = Exp(-w dt) dtheta - Jr(w dt) dt dbg
//   dv+     = dv + (-R [a]x dtheta - R dba + dg) dt,   dp+ = dp + dv dt
// and P+ = F P F^T + Q with Q from the continuous noise densities.
void Ieskf::Step(const Eigen::Vector3d& gyro_imu, const Eigen::Vector3d& acc_imu, double dt_s) {
  const Eigen::Vector3d w = gyro_imu - x_.bg;
  const Eigen::Vector3d a = acc_imu - x_.ba;
  // The specific force is rotated with the mid-interval attitude: second
  // order in dt, where the start attitude would bias a turning trajectory.
  const Eigen::Matrix3d R = x_.R_world_imu * so3::Exp(0.5 * w * dt_s);
  const Eigen::Vector3d a_world = R * a + x_.g_world;

  Matrix24d F = Matrix24d::Identity();
  const Eigen::Vector3d w_dt = w * dt_s;
  F.block<3, 3>(FilterState::kRot, FilterState::kRot) = so3::Exp(-w_dt);
  F.block<3, 3>(FilterState::kRot, FilterState::kBg) = -so3::Jr(w_dt) * dt_s;
  F.block<3, 3>(FilterState::kPos, FilterState::kVel) = Eigen::Matrix3d::Identity() * dt_s;
  F.block<3, 3>(FilterState::kVel, FilterState::kRot) = -R * so3::Hat(a) * dt_s;
  F.block<3, 3>(FilterState::kVel, FilterState::kBa) = -R * dt_s;
  F.block<3, 3>(FilterState::kVel, FilterState::kGrav) = Eigen::Matrix3d::Identity() * dt_s;

  x_.p_world_imu += x_.v_world_imu * dt_s + 0.5 * a_world * dt_s * dt_s;
  x_.v_world_imu += a_world * dt_s;
  x_.R_world_imu = x_.R_world_imu * so3::Exp(w_dt);

  PropagateCovariance(F, imu_, dt_s, &P_);
  state_kind_.propagate(F, dt_s, lidar_, &td_);
  if (options_.estimate_extrinsics) {
    PropagateCovariance(F, imu_, dt_s, &P_all_extrinsic_);
    AddExtrinsicRandomWalk(dt_s);
  }
}

// Only released axes: a held axis keeps its tiny variance (see ReleaseExcitedAxes).
void Ieskf::AddExtrinsicRandomWalk(double dt_s) {
  for (int i = 0; i < 6; ++i) {
    if (!released_[i]) continue;
    const double q = i < 3 ? options_.extrinsic_rot_random_walk : options_.extrinsic_pos_random_walk;
    P_(FilterState::kExtRot + i, FilterState::kExtRot + i) += q * q * dt_s;
  }
}

// Iterated update, paper Eq. (1), in information form. With
//   e = J^-1 (x^v [-] x^0),  Pv = J^-1 P J^-T  (Eq. 2),
// the increment minimizing |z + H d|^2_R + |e + d|^2_Pv is
//   d = -(H^T R^-1 H + Pv^-1)^-1 (H^T R^-1 z + Pv^-1 e),
// which equals -K z - (I - K H) e of Eq. (1); the posterior covariance
// (I - K H) Pv equals (H^T R^-1 H + Pv^-1)^-1.
IeskfUpdateResult Ieskf::Update(const AssociateFn& associate) {
  return (this->*state_kind_.update)(associate);
}

// The motion held at the state's time: the newest pose sample's (the IMU
// measurement held by the last propagation step).
ScanTimeMotion Ieskf::MotionAtStateTime() const {
  ScanTimeMotion m;
  if (pose_history_.empty()) return m;
  m.gyro_imu = pose_history_.samples().back().gyro_imu;
  m.acc_world = pose_history_.samples().back().acc_world;
  return m;
}

// StatePolicy: the optional states (state_policies.h), NoTimeOffsetState
// or TimeOffsetState; the extrinsic columns from ExtrinsicColumnsNow().
template <class StatePolicy>
IeskfUpdateResult Ieskf::UpdateImpl(const AssociateFn& associate) {
  using MatrixN = typename StatePolicy::MatrixN;
  using VectorN = typename StatePolicy::VectorN;
  IeskfUpdateResult result;
  result.degeneracy.method = degeneracy_.method;  // also when no iteration runs
  if (options_.estimate_extrinsics) ReleaseExcitedAxes();
  const FilterState x0 = x_;
  StatePolicy state(StateUpdateStart{P_, x0, ExtrinsicColumnsNow(), &td_, MotionAtStateTime(),
                                     lidar_.time_offset_max});
  const MatrixN P0 = state.Prior();
  const MatrixN P0_inv = P0.ldlt().solve(MatrixN::Identity());
  const double inv_sigma2 = 1.0 / (constraints_.lidar_noise * constraints_.lidar_noise);
  Matrix24d J = Matrix24d::Identity();

  FilterState x = x0;
  MatrixN S = P0;
  ConstraintList constraints;
  typename StatePolicy::MatrixC HtRinvH;
  typename StatePolicy::VectorC HtRinvz;
  for (int it = 0; it < options_.max_iterations; ++it) {
    const FilterState x_scan = state.AtScanTime(x);
    associate(x_scan, &constraints);
    // Alg. 3: criterion, reinforcement, repair; a no-op edit when RV is off
    // (the report still carries the localizability figure).
    result.rv = ApplyRv(rv_, x_scan.T_world_lidar(), &constraints, &rv_workspace_);
    result.num_constraints = static_cast<int>(constraints.size());
    if (result.num_constraints < kMinPoseConstraints) break;
    double zRinvz = 0.0;
    state.Accumulate(constraints, x_scan, inv_sigma2, &HtRinvH, &HtRinvz, &zRinvz);
    const DegeneracyTreatment degeneracy =
        AnalyzeScanDegeneracy(degeneracy_, result.rv, HtRinvH, inv_sigma2, constraints, x_scan);
    result.degeneracy = degeneracy.report;

    J = BoxminusJacobian(x, x0);
    const VectorN e = state.PriorError(BoxminusJacobianInverse(x, x0), x, x0);
    const MatrixN Jn = state.Lift(J);
    const MatrixN Pv_inv = Jn.transpose() * P0_inv * Jn;
    MatrixN A = Pv_inv;
    VectorN b = Pv_inv * e;
    state.AddColumns(HtRinvH, HtRinvz, &A, &b);
    const Eigen::LDLT<MatrixN> ldlt(A);
    VectorN dx = -ldlt.solve(b);
    S = ldlt.solve(MatrixN::Identity());
    // At x = x0 (e = 0): z^T (H P0 H^T + R)^-1 z = z^T R^-1 z - b^T A^-1 b = z^T R^-1 z + b^T dx.
    if (it == 0) {
      result.nis_per_dof = (zRinvz + b.dot(dx)) / result.num_constraints;
      result.lidar_rotation_imu = LidarOnlyRotation(HtRinvH, HtRinvz);
    }
    // The degeneracy method acts on the increment; the covariance S stays
    // the plain posterior (docs/degeneracy.md).
    TreatIncrement(degeneracy_.method, degeneracy, inv_sigma2, A, b, &dx);
    x = Boxplus(x, dx.template head<24>());
    state.Apply(dx);
    result.iterations = it + 1;
    result.last_step_norm = dx.norm();
    if (!dx.allFinite()) break;
    if (result.last_step_norm < options_.convergence_eps) break;
  }
  if (result.iterations == 0) return result;  // too few constraints: prediction only
  S = 0.5 * (S + S.transpose());
  if (!IsHealthy(x, S.template topLeftCorner<24, 24>()) || !state.finite()) {
    result.diverged = true;  // keep the prior (x0, P0): the last good state
    return result;
  }
  x_ = x;
  state.Commit(S, &P_);
  if (options_.estimate_extrinsics) UpdateExcitation(HtRinvH.template topLeftCorner<12, 12>(), J);
  result.ok = true;
  const FilterState x_scan = state.AtScanTime(x_);
  result.residuals = ComputeResidualStats(constraints, x_scan.T_world_imu(), x_scan.T_imu_lidar());
  return result;
}

// The extrinsic columns of this update: with estimate_extrinsics, the axes
// excited so far.
ExtrinsicColumns Ieskf::ExtrinsicColumnsNow() const {
  ExtrinsicColumns c;
  c.estimated = options_.estimate_extrinsics;
  for (int i = 0; i < 6; ++i) c.free[i] = c.estimated && excitation_.excited(i);
  return c;
}

// A held extrinsic axis carries the tiny kFixedExtrinsicStd in P (a loose
// variance on an axis without a Jacobian column would still let the
// increments leak into it through the rotation Jacobians of the iteration);
// once excited it gets its prior variance, uncorrelated, and its column.
void Ieskf::ReleaseExcitedAxes() {
  const Vector6d prior_std = ExtrinsicPriorStd(options_);
  for (int i = 0; i < 6; ++i) {
    if (released_[i] || !excitation_.excited(i)) continue;
    const int k = FilterState::kExtRot + i;
    P_.row(k).setZero();
    P_.col(k).setZero();
    P_(k, k) = prior_std(i) * prior_std(i);
    released_[i] = true;
  }
}

// The covariance the update would leave with every extrinsic axis estimated
// (same linearization as the last iteration), in information form as in
// Update(); its extrinsic block drives the excitation monitor.
void Ieskf::UpdateExcitation(const Eigen::Matrix<double, 12, 12>& HtRinvH, const Matrix24d& J) {
  std::array<bool, 6> all;
  all.fill(true);
  const Matrix24x12d E = ErrorStateColumns(all);
  const Matrix24d prior_inv = P_all_extrinsic_.ldlt().solve(Matrix24d::Identity());
  const Matrix24d A = J.transpose() * prior_inv * J + E * HtRinvH * E.transpose();
  Matrix24d S = A.ldlt().solve(Matrix24d::Identity());
  S = 0.5 * (S + S.transpose());
  if (!S.allFinite()) return;
  P_all_extrinsic_ = S;
  excitation_.Observe(S.block<6, 6>(FilterState::kExtRot, FilterState::kExtRot));
}

}  // namespace rvlio
