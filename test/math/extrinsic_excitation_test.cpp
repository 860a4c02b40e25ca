// The extrinsic excitation monitor: covariance ratio and rotational
// (hand-eye) excitation must both hold before an axis is released.
#include "rvlio/math/extrinsic_excitation.h"

#include <gtest/gtest.h>

#include "rvlio/math/so3.h"

namespace rvlio {
namespace {

constexpr TimeNs kScanNs = 100000000;  // 10 Hz

// Covariance far below the prior on every axis (the update's view).
Matrix6d Tight(const Vector6d& prior_std) {
  return (0.01 * prior_std).cwiseAbs2().asDiagonal();
}

ExtrinsicExcitation RunAtRate(const Eigen::Vector3d& rate_imu, int scans) {
  Vector6d prior_std;
  prior_std << 0.05, 0.05, 0.05, 0.1, 0.1, 0.1;
  ExtrinsicExcitation e(prior_std);
  for (int k = 0; k < scans; ++k) {
    const Eigen::Matrix3d R = so3::Exp(rate_imu * (k * 0.1));
    e.Observe(Tight(prior_std));
    e.CountScan(k * kScanNs, R, Eigen::Matrix3d::Identity());
  }
  return e;
}

TEST(ExtrinsicExcitation, StaticMotionExcitesNothingWhateverTheCovariance) {
  const ExtrinsicExcitation e = RunAtRate(Eigen::Vector3d::Zero(), 300);
  for (int i = 0; i < 6; ++i) EXPECT_FALSE(e.excited(i)) << i;
  EXPECT_FALSE(e.any_excited());
  EXPECT_EQ(e.excited_fraction(), 0.0);
  EXPECT_LT(e.std_ratio().maxCoeff(), 0.5);  // the covariance alone would have released them
}

TEST(ExtrinsicExcitation, YawOnlyLeavesTheYawAxesHeld) {
  // 0.3 rad/s about z for 20 s: offsets about / along z stay unobservable.
  const ExtrinsicExcitation e = RunAtRate(Eigen::Vector3d(0, 0, 0.3), 200);
  EXPECT_TRUE(e.excited(0));
  EXPECT_TRUE(e.excited(1));
  EXPECT_FALSE(e.excited(2));
  EXPECT_TRUE(e.excited(3));
  EXPECT_TRUE(e.excited(4));
  EXPECT_FALSE(e.excited(5));
  EXPECT_GT(e.excited_fraction(), 0.3);
  EXPECT_LT(e.excited_fraction(), 4.0 / 6.0);
}

TEST(ExtrinsicExcitation, TwoRotationAxesExciteAllAndTheCovarianceStillGates) {
  Vector6d prior_std;
  prior_std << 0.05, 0.05, 0.05, 0.1, 0.1, 0.1;
  ExtrinsicExcitation e(prior_std);
  Matrix6d loose = prior_std.cwiseAbs2().asDiagonal();
  loose(5, 5) *= 0.9;  // pos_z: hardly any information from the updates
  for (int k = 0; k < 200; ++k) {
    const double t = k * 0.1;
    const Eigen::Matrix3d R = so3::Exp(Eigen::Vector3d(0.3 * std::sin(t), 0.0, 0.3 * t));
    e.Observe(k < 100 ? loose : Tight(prior_std));
    e.CountScan(k * kScanNs, R, Eigen::Matrix3d::Identity());
    if (k == 99) {
      for (int i = 0; i < 6; ++i) EXPECT_FALSE(e.excited(i)) << "covariance not yet tight, " << i;
    }
  }
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(e.excited(i)) << i;
}

}  // namespace
}  // namespace rvlio
