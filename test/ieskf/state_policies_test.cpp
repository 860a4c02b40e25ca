// The IESKF's state policies (src/ieskf/state_policies.h): where each puts
// the Jacobian columns in its error state, the time offset's rule at rest,
// its increment and its bound.
#include <cmath>

#include <gtest/gtest.h>

#include "state_policies.h"

namespace rvlio {
namespace {

// A symmetric positive definite C x C matrix with distinct entries.
template <int C>
Eigen::Matrix<double, C, C> SomeInformation() {
  Eigen::Matrix<double, C, C> M;
  for (int i = 0; i < C; ++i)
    for (int j = 0; j < C; ++j) M(i, j) = std::sin(1.0 + i + 7.0 * j);
  return M.transpose() * M + Eigen::Matrix<double, C, C>::Identity();
}

template <int C>
Eigen::Matrix<double, C, 1> SomeGradient() {
  Eigen::Matrix<double, C, 1> g;
  for (int i = 0; i < C; ++i) g(i) = 1.0 + i;
  return g;
}

struct PolicyFixture {
  Matrix24d P = Matrix24d::Identity();
  FilterState x0;
  TimeOffsetEstimate td;
  StateUpdateStart Start(const ExtrinsicColumns& ext, const ScanTimeMotion& motion,
                         double td_max_s = 0.1) {
    return StateUpdateStart{P, x0, ext, &td, motion, td_max_s};
  }
};

TEST(IeskfStatePolicies, FixedExtrinsicFillsThePoseBlockOnly) {
  PolicyFixture f;
  const NoTimeOffsetState state(f.Start(ExtrinsicColumns(), ScanTimeMotion()));
  const auto H = SomeInformation<12>();
  const auto g = SomeGradient<12>();
  Matrix24d A = Matrix24d::Zero();
  Vector24d b = Vector24d::Zero();
  state.AddColumns(H, g, &A, &b);
  EXPECT_TRUE((A.topLeftCorner<6, 6>() == H.topLeftCorner<6, 6>()));
  Matrix24d rest = A;
  rest.topLeftCorner<6, 6>().setZero();
  EXPECT_EQ(rest.norm(), 0.0);
  EXPECT_TRUE(b.head<6>() == g.head<6>());
  EXPECT_EQ(b.tail<18>().norm(), 0.0);
}

TEST(IeskfStatePolicies, EstimatedExtrinsicFillsTheFreeAxesOnly) {
  PolicyFixture f;
  ExtrinsicColumns ext;
  ext.estimated = true;
  ext.free = {true, false, false, false, false, true};
  const NoTimeOffsetState state(f.Start(ext, ScanTimeMotion()));
  const auto H = SomeInformation<12>();
  const auto g = SomeGradient<12>();
  Matrix24d A = Matrix24d::Zero();
  Vector24d b = Vector24d::Zero();
  state.AddColumns(H, g, &A, &b);
  const int rot0 = FilterState::kExtRot, pos2 = FilterState::kExtPos + 2;
  EXPECT_TRUE((A.topLeftCorner<6, 6>() == H.topLeftCorner<6, 6>()));
  EXPECT_EQ(A(rot0, rot0), H(6, 6));
  EXPECT_EQ(A(pos2, pos2), H(11, 11));
  EXPECT_EQ(A(FilterState::kPos, pos2), H(3, 11));
  EXPECT_EQ(b(pos2), g(11));
  EXPECT_EQ(A.row(rot0 + 1).norm(), 0.0);  // held axis: no column
  EXPECT_EQ(b(rot0 + 1), 0.0);
}

TEST(IeskfStatePolicies, TimeOffsetColumnOnlyWhenTheMotionShowsIt) {
  const auto H = SomeInformation<16>();
  const auto g = SomeGradient<16>();
  const int td = TimeOffsetState::kIndex;
  for (const double rate : {0.0, 0.5}) {
    PolicyFixture f;
    ScanTimeMotion motion;
    motion.gyro_imu = Eigen::Vector3d(0.0, 0.0, rate);
    const TimeOffsetState state(f.Start(ExtrinsicColumns(), motion));
    const bool moving = rate > 0.0;
    EXPECT_EQ(f.td.observed, moving);
    TimeOffsetState::MatrixN A = TimeOffsetState::MatrixN::Zero();
    TimeOffsetState::VectorN b = TimeOffsetState::VectorN::Zero();
    state.AddColumns(H, g, &A, &b);
    EXPECT_EQ(A(FilterState::kVel, FilterState::kVel), H(12, 12));  // dv column
    EXPECT_EQ(A(FilterState::kRot, FilterState::kVel + 2), H(0, 14));
    EXPECT_EQ(A(td, td), moving ? H(15, 15) : 0.0);
    EXPECT_EQ(A(FilterState::kPos, td), moving ? H(3, 15) : 0.0);
    EXPECT_EQ(b(td), moving ? g(15) : 0.0);
    EXPECT_EQ(A.row(FilterState::kExtRot).norm(), 0.0);  // extrinsic fixed
  }
}

TEST(IeskfStatePolicies, TimeOffsetIncrementPriorErrorAndBound) {
  PolicyFixture f;
  f.td.td_s = 0.01;
  f.td.P_x_td(3) = 1e-4;
  f.td.P_td_td = 4e-4;
  ScanTimeMotion motion;
  motion.gyro_imu = Eigen::Vector3d(0.3, 0.0, 0.0);
  TimeOffsetState state(f.Start(ExtrinsicColumns(), motion, 0.05));
  EXPECT_EQ(f.td.td_lin_s, 0.01);  // the scan is linearized at the offset it was deskewed with
  const TimeOffsetState::MatrixN P0 = state.Prior();
  EXPECT_EQ(P0(24, 24), 4e-4);
  EXPECT_EQ(P0(3, 24), 1e-4);
  EXPECT_EQ(P0(24, 3), 1e-4);

  TimeOffsetState::VectorN dx = TimeOffsetState::VectorN::Zero();
  dx(TimeOffsetState::kIndex) = 0.02;
  state.Apply(dx);
  EXPECT_DOUBLE_EQ(state.PriorError(Matrix24d::Identity(), f.x0, f.x0)(24), 0.02);
  EXPECT_TRUE(state.finite());

  dx(TimeOffsetState::kIndex) = 0.1;  // to 0.13, past the bound 0.05
  state.Apply(dx);
  TimeOffsetState::MatrixN S = 2.0 * TimeOffsetState::MatrixN::Identity();
  S(24, 24) = 9e-4;
  state.Commit(S, &f.P);
  EXPECT_EQ(f.td.td_s, 0.05);
  EXPECT_EQ(f.td.P_td_td, 9e-4);
  EXPECT_TRUE(f.P == 2.0 * Matrix24d::Identity());
}

}  // namespace
}  // namespace rvlio
