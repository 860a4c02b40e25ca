// The window's scan factor kinds (src/window/scan_factor.h): each kind's
// factor has the parameter blocks the kind names, in its order, and a scan
// whose summary overflows makes no factor.
#include <gtest/gtest.h>

#include "scan_factor.h"

namespace rvlio {
namespace {

// Eight points on three walls around the origin.
ConstraintList SomeConstraints() {
  ConstraintList list;
  for (int i = 0; i < 8; ++i) {
    Constraint c;
    c.p_lidar = Eigen::Vector3d(1.0 + i, 0.5 * i, 2.0 - 0.25 * i);
    c.normal_world = Eigen::Vector3d::Unit(i % 3);
    c.q_world = c.p_lidar + 0.01 * c.normal_world;
    list.push_back(c);
  }
  return list;
}

struct KindCase {
  bool estimate_extrinsics;
  bool estimate_time_offset;
  std::vector<int> sizes;  // PoseBlock 7, SpeedBiasBlock 9, offset 1
};

TEST(WindowScanFactor, EachKindNamesItsFactorsBlocks) {
  double pose[7], sb[9], extrinsic[7], td[1];
  const ScanFactorBlocks blocks{pose, sb, extrinsic, td};
  const std::vector<KindCase> cases = {
      {false, false, {7}}, {true, false, {7, 7}}, {false, true, {7, 9, 1}}};
  const ConstraintList constraints = SomeConstraints();
  const Pose3 T_imu_lidar;
  const ScanTimeMotion motion;
  const Eigen::Vector3d center = Eigen::Vector3d::Zero();
  for (const KindCase& c : cases) {
    const auto kind = MakeScanFactorKind(c.estimate_extrinsics, c.estimate_time_offset);
    const auto factor = kind->Make({constraints, 0.02, T_imu_lidar, motion, 0.0, center});
    ASSERT_NE(factor, nullptr);
    const std::vector<double*> named = kind->Blocks(blocks);
    EXPECT_EQ(factor->parameter_block_sizes(), c.sizes);
    const std::vector<double*> expected =
        c.estimate_extrinsics    ? std::vector<double*>{pose, extrinsic}
        : c.estimate_time_offset ? std::vector<double*>{pose, sb, td}
                                 : std::vector<double*>{pose};
    EXPECT_EQ(named, expected);
  }
}

TEST(WindowScanFactor, OverflowingSummaryMakesNoFactor) {
  ConstraintList constraints = SomeConstraints();
  constraints.front().q_world = Eigen::Vector3d::Constant(1e300);
  const Pose3 T_imu_lidar;
  const ScanTimeMotion motion;
  const Eigen::Vector3d center = Eigen::Vector3d::Zero();
  const ScanFactorInput input{constraints, 0.02, T_imu_lidar, motion, 0.0, center};
  EXPECT_EQ(MakeScanFactorKind(false, false)->Make(input), nullptr);
  EXPECT_EQ(MakeScanFactorKind(false, true)->Make(input), nullptr);
  EXPECT_NE(MakeScanFactorKind(false, false)->Make({SomeConstraints(), 0.02, T_imu_lidar, motion,
                                                    0.0, center}),
            nullptr);
}

}  // namespace
}  // namespace rvlio
