#include "state_policies.h"

#include <cmath>

#include "rvlio/constraints/point_to_plane.h"

namespace rvlio {
namespace {

using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Vector12d = Eigen::Matrix<double, 12, 1>;

// Accumulates H^T R^-1 H and H^T R^-1 z over the constraints (paper Eq. 1).
// Columns: [dtheta, dp] and, when extrinsics are estimated, [dphi, dt].
void AccumulatePoseExtrinsicColumns(const ConstraintList& constraints, const FilterState& x,
                                    bool with_extrinsics, double inv_sigma2, Matrix12d* HtRinvH,
                                    Vector12d* HtRinvz, double* zRinvz) {
  HtRinvH->setZero();
  HtRinvz->setZero();
  *zRinvz = 0.0;
  const Pose3 T_world_imu = x.T_world_imu(), T_imu_lidar = x.T_imu_lidar();
  Eigen::Matrix<double, 1, 12> h;
  for (const Constraint& c : constraints) {
    const double r = PointToPlaneResidualWithExtrinsics(c, T_world_imu, T_imu_lidar, &h);
    const double w = c.weight * inv_sigma2;
    *zRinvz += w * r * r;
    if (with_extrinsics) {
      HtRinvH->noalias() += w * h.transpose() * h;
      HtRinvz->noalias() += w * r * h.transpose();
    } else {
      const auto h6 = h.leftCols<6>();
      HtRinvH->topLeftCorner<6, 6>().noalias() += w * h6.transpose() * h6;
      HtRinvz->head<6>().noalias() += w * r * h6.transpose();
    }
  }
}

// The rows of TimeOffsetJacobian's 16 columns in the 25-dim augmented error
// state [FilterState, td]; -1 for an extrinsic axis held fixed.
std::array<int, 16> TimeOffsetErrorStateRows(const std::array<bool, 6>& free) {
  std::array<int, 16> rows{};
  for (int i = 0; i < 3; ++i) {
    rows[i] = FilterState::kRot + i;
    rows[3 + i] = FilterState::kPos + i;
    rows[12 + i] = FilterState::kVel + i;
  }
  for (int i = 0; i < 6; ++i) rows[6 + i] = free[i] ? FilterState::kExtRot + i : -1;
  rows[15] = TimeOffsetState::kIndex;
  return rows;
}

// A += E H E^T, b += E g for a column map E with one 1 per used column:
// index[c] is the error-state row of column c, -1 for an unused column.
template <int N, int C>
void ScatterNormalEquations(const std::array<int, C>& index, const Eigen::Matrix<double, C, C>& H,
                            const Eigen::Matrix<double, C, 1>& g,
                            Eigen::Matrix<double, N, N>* A, Eigen::Matrix<double, N, 1>* b) {
  for (int i = 0; i < C; ++i) {
    if (index[i] < 0) continue;
    (*b)(index[i]) += g(i);
    for (int j = 0; j < C; ++j)
      if (index[j] >= 0) (*A)(index[i], index[j]) += H(i, j);
  }
}

// The motion a scan's time offset is observed through (its Jacobian column
// h_theta w + h_p v): below these, at rest within the IMU noise.
constexpr double kTimeOffsetMinRate = 0.05;   // rad/s
constexpr double kTimeOffsetMinSpeed = 0.05;  // m/s

}  // namespace

bool TimeOffsetObservable(const Eigen::Vector3d& v_world_imu, const ScanTimeMotion& motion) {
  return motion.gyro_imu.norm() >= kTimeOffsetMinRate || v_world_imu.norm() >= kTimeOffsetMinSpeed;
}

void NoTimeOffsetState::Start(const LidarOptions& lidar, TimeOffsetEstimate* td) {
  *td = TimeOffsetEstimate();
  td->td_s = td->td_lin_s = lidar.time_offset;
}

NoTimeOffsetState::NoTimeOffsetState(const StateUpdateStart& start)
    : P_(start.P), extrinsic_(start.extrinsic), E_(ErrorStateColumns(start.extrinsic.free)) {}

void NoTimeOffsetState::Accumulate(const ConstraintList& constraints, const FilterState& x_scan,
                                   double inv_sigma2, MatrixC* HtRinvH, VectorC* HtRinvz,
                                   double* zRinvz) const {
  AccumulatePoseExtrinsicColumns(constraints, x_scan, extrinsic_.estimated, inv_sigma2, HtRinvH,
                                 HtRinvz, zRinvz);
}

NoTimeOffsetState::VectorN NoTimeOffsetState::PriorError(const Matrix24d& J_inv,
                                                         const FilterState& x,
                                                         const FilterState& x0) const {
  return J_inv * Boxminus(x, x0);
}

// Estimated extrinsics: the 12 columns through ErrorStateColumns (held axes
// have none); else the pose block alone.
void NoTimeOffsetState::AddColumns(const MatrixC& HtRinvH, const VectorC& HtRinvz, MatrixN* A,
                                   VectorN* b) const {
  if (extrinsic_.estimated) {
    A->noalias() += E_ * HtRinvH * E_.transpose();
    b->noalias() += E_ * HtRinvz;
    return;
  }
  const int cols = 6;
  A->topLeftCorner(cols, cols) += HtRinvH.topLeftCorner(cols, cols);
  b->head(cols) += HtRinvz.head(cols);
}

// At rest the offset's column (w, v) is IMU noise alone: no update of the
// offset (it would fit the noise and leave a confident wrong value for the
// motion to undo).
void TimeOffsetState::Start(const LidarOptions& lidar, TimeOffsetEstimate* td) {
  NoTimeOffsetState::Start(lidar, td);
  td->P_td_td = lidar.time_offset_init_std * lidar.time_offset_init_std;
}

void TimeOffsetState::Propagate(const Matrix24d& F, double dt_s, const LidarOptions& lidar,
                                TimeOffsetEstimate* td) {
  td->P_x_td = F * td->P_x_td;
  td->P_td_td += lidar.time_offset_random_walk * lidar.time_offset_random_walk * dt_s;
}

TimeOffsetState::TimeOffsetState(const StateUpdateStart& start)
    : P_(start.P),
      extrinsic_(start.extrinsic),
      td_(start.time_offset),
      td_max_s_(start.time_offset_max_s),
      td_s_(start.time_offset->td_s),
      rows_(TimeOffsetErrorStateRows(start.extrinsic.free)) {
  td_->td_lin_s = td_->td_s;
  td_->scan_motion = start.motion;
  td_->observed = TimeOffsetObservable(start.x0.v_world_imu, td_->scan_motion);
  if (!td_->observed) rows_[kCols - 1] = -1;
}

TimeOffsetState::MatrixN TimeOffsetState::Prior() const {
  MatrixN P0;
  P0 << P_, td_->P_x_td, td_->P_x_td.transpose(), td_->P_td_td;
  return P0;
}

// The state moved to the scan's time td - td_lin after it (lin_: the
// linearization Accumulate uses).
FilterState TimeOffsetState::AtScanTime(const FilterState& x) {
  lin_ = LinearizeAtScanTime(x, td_->scan_motion, td_s_ - td_->td_lin_s);
  FilterState moved = x;
  moved.R_world_imu = lin_.T_world_imu.R;
  moved.p_world_imu = lin_.T_world_imu.t;
  return moved;
}

// The sums of the 12 columns at the scan-time pose (the same per-constraint
// work as without the offset) mapped once to the 16 columns
// (ScanTimeLinearization::h_to_J); extrinsic columns zero unless estimated.
void TimeOffsetState::Accumulate(const ConstraintList& constraints, const FilterState& x_scan,
                                 double inv_sigma2, MatrixC* HtRinvH, VectorC* HtRinvz,
                                 double* zRinvz) const {
  Matrix12d H12;
  Vector12d b12;
  AccumulatePoseExtrinsicColumns(constraints, x_scan, extrinsic_.estimated, inv_sigma2, &H12,
                                 &b12, zRinvz);
  HtRinvH->noalias() = lin_.h_to_J.transpose() * H12 * lin_.h_to_J;
  HtRinvz->noalias() = lin_.h_to_J.transpose() * b12;
}

TimeOffsetState::VectorN TimeOffsetState::PriorError(const Matrix24d& J_inv, const FilterState& x,
                                                     const FilterState& x0) const {
  VectorN e;
  e << J_inv * Boxminus(x, x0), td_s_ - td_->td_s;
  return e;
}

TimeOffsetState::MatrixN TimeOffsetState::Lift(const Matrix24d& J) const {
  MatrixN Jn;
  Jn.setIdentity();
  Jn.topLeftCorner<24, 24>() = J;
  return Jn;
}

void TimeOffsetState::AddColumns(const MatrixC& HtRinvH, const VectorC& HtRinvz, MatrixN* A,
                                 VectorN* b) const {
  ScatterNormalEquations<kDim, kCols>(rows_, HtRinvH, HtRinvz, A, b);
}

bool TimeOffsetState::finite() const { return std::isfinite(td_s_); }

// An estimate past +-time_offset_max is held at the bound (reported:
// Ieskf::time_offset_at_bound()); the state's pose is left as the update made it.
void TimeOffsetState::Commit(const MatrixN& S, Matrix24d* P) const {
  *P = S.topLeftCorner<24, 24>();
  td_->P_x_td = S.col(kIndex).head<24>();
  td_->P_td_td = S(kIndex, kIndex);
  td_->td_s = td_s_;
  if (std::abs(td_->td_s) > td_max_s_) td_->td_s = std::copysign(td_max_s_, td_->td_s);
}

}  // namespace rvlio
