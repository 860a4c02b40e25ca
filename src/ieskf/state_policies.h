#pragma once
// The optional states of the IESKF update as policy types (docs/design.md,
// "Features as policies"). Ieskf::UpdateImpl<StatePolicy> is the iterated
// update of paper Eq. (1) written once; what an optional state changes in it
// is a type, chosen once when the filter is made (Ieskf::StateKind):
//   NoTimeOffsetState  the 24-dim error state of FilterState; 12 Jacobian
//                      columns [dtheta, dp, dphi, dt] at the state's pose
//   TimeOffsetState    augmented with the LiDAR-IMU time offset (entry 24);
//                      the residuals at the scan's time, the 16 columns of
//                      TimeOffsetJacobian [dtheta, dp, dphi, dt, dv, d(td)]
// A policy has
//   Start(lidar, &td)                its entries when the filter starts
//   Propagate(F, dt, lidar, &td)     its covariance over one IMU step
//   kDim, kCols, MatrixN/VectorN (error state), MatrixC/VectorC (columns)
//   Policy(const StateUpdateStart&)  begins a scan's update
//   Prior()                          P0 of its error state
//   AtScanTime(x)                    the state association, RV and the residuals see
//   Accumulate(...)                  H^T R^-1 H, H^T R^-1 z, z^T R^-1 z over its columns
//   PriorError(J_inv, x, x0)         e = J^-1 (x [-] x0) in its error state
//   Lift(J)                          the Boxminus Jacobian in its error state
//   AddColumns(H, g, &A, &b)         its columns into the normal equations
//   Apply(dx)                        the increment of its own entries
//   finite()                         its own entries are finite (else: diverged)
//   Commit(S, &P)                    the posterior of P and of its own entries
// A new kind of state is a new type with these members; UpdateImpl stays.
// The estimated extrinsic is no type of its own: ExtrinsicColumns says which
// extrinsic columns the update estimates, and each policy places them.
#include <array>

#include <Eigen/Core>

#include "rvlio/constraints/constraint.h"
#include "rvlio/constraints/time_offset_residual.h"
#include "rvlio/ieskf/ieskf.h"
#include "rvlio/imu/filter_state.h"

namespace rvlio {

// The extrinsic columns of an update (ieskf.estimate_extrinsics): estimated,
// the Jacobian has the 12 columns [dtheta, dp, dphi, dt] and an extrinsic
// axis enters the update once excited (free); else the pose columns alone.
struct ExtrinsicColumns {
  bool estimated = false;
  std::array<bool, 6> free{};
};

// What a policy begins a scan's update from.
struct StateUpdateStart {
  const Matrix24d& P;               // the filter's covariance before the update
  const FilterState& x0;            // the prediction
  ExtrinsicColumns extrinsic;
  TimeOffsetEstimate* time_offset;  // the filter's offset (TimeOffsetState writes it)
  ScanTimeMotion motion;            // the motion held at the state's time
  double time_offset_max_s;         // lidar.time_offset_max
};

// Whether a scan shows the time offset: its Jacobian column h_theta w + h_p v
// is not IMU noise alone (at rest).
bool TimeOffsetObservable(const Eigen::Vector3d& v_world_imu, const ScanTimeMotion& motion);

// The 24-dim filter of paper Eq. (1) as it is: the offset stays at its value.
class NoTimeOffsetState {
 public:
  static constexpr int kDim = 24;
  static constexpr int kCols = 12;
  using MatrixN = Eigen::Matrix<double, kDim, kDim>;
  using VectorN = Eigen::Matrix<double, kDim, 1>;
  using MatrixC = Eigen::Matrix<double, kCols, kCols>;
  using VectorC = Eigen::Matrix<double, kCols, 1>;

  // The offset at lidar.time_offset, not estimated (variance 0).
  static void Start(const LidarOptions& lidar, TimeOffsetEstimate* td);
  static void Propagate(const Matrix24d&, double, const LidarOptions&, TimeOffsetEstimate*) {}

  explicit NoTimeOffsetState(const StateUpdateStart& start);
  MatrixN Prior() const { return P_; }
  FilterState AtScanTime(const FilterState& x) const { return x; }
  void Accumulate(const ConstraintList& constraints, const FilterState& x_scan, double inv_sigma2,
                  MatrixC* HtRinvH, VectorC* HtRinvz, double* zRinvz) const;
  VectorN PriorError(const Matrix24d& J_inv, const FilterState& x, const FilterState& x0) const;
  MatrixN Lift(const Matrix24d& J) const { return J; }
  void AddColumns(const MatrixC& HtRinvH, const VectorC& HtRinvz, MatrixN* A, VectorN* b) const;
  void Apply(const VectorN&) {}
  bool finite() const { return true; }
  void Commit(const MatrixN& S, Matrix24d* P) const { *P = S; }

 private:
  const Matrix24d& P_;
  ExtrinsicColumns extrinsic_;
  Eigen::Matrix<double, 24, 12> E_;  // ErrorStateColumns(free), with estimated extrinsics
};

// The error state augmented with the time offset td (entry kIndex): the
// residuals at the scan's time, linearized per iteration at the iterate's
// offset (LinearizeAtScanTime); the offset is not updated from a scan taken
// at rest (TimeOffsetObservable) and is held at +-time_offset_max.
class TimeOffsetState {
 public:
  static constexpr int kDim = 25;
  static constexpr int kCols = 16;
  static constexpr int kIndex = FilterState::kDim;  // the offset's error-state entry
  using MatrixN = Eigen::Matrix<double, kDim, kDim>;
  using VectorN = Eigen::Matrix<double, kDim, 1>;
  using MatrixC = Eigen::Matrix<double, kCols, kCols>;
  using VectorC = Eigen::Matrix<double, kCols, 1>;

  // The offset at lidar.time_offset with variance time_offset_init_std^2.
  static void Start(const LidarOptions& lidar, TimeOffsetEstimate* td);
  // Its cross covariance through F (the offset itself is constant: an
  // identity row) and its random walk (lidar.time_offset_random_walk).
  static void Propagate(const Matrix24d& F, double dt_s, const LidarOptions& lidar,
                        TimeOffsetEstimate* td);

  // Sets the filter's offset linearization point and scan motion to this scan's.
  explicit TimeOffsetState(const StateUpdateStart& start);
  MatrixN Prior() const;
  FilterState AtScanTime(const FilterState& x);
  void Accumulate(const ConstraintList& constraints, const FilterState& x_scan, double inv_sigma2,
                  MatrixC* HtRinvH, VectorC* HtRinvz, double* zRinvz) const;
  VectorN PriorError(const Matrix24d& J_inv, const FilterState& x, const FilterState& x0) const;
  MatrixN Lift(const Matrix24d& J) const;
  void AddColumns(const MatrixC& HtRinvH, const VectorC& HtRinvz, MatrixN* A, VectorN* b) const;
  void Apply(const VectorN& dx) { td_s_ += dx(kIndex); }
  bool finite() const;
  void Commit(const MatrixN& S, Matrix24d* P) const;

 private:
  const Matrix24d& P_;
  ExtrinsicColumns extrinsic_;
  TimeOffsetEstimate* td_;
  double td_max_s_;
  double td_s_;                  // the iterate's offset
  ScanTimeLinearization lin_;    // at the last AtScanTime
  std::array<int, kCols> rows_;  // the error-state row of each column, -1: not estimated
};

}  // namespace rvlio
