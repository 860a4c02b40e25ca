#include "scan_factor.h"

#include "rvlio/factors/parameter_blocks.h"
#include "rvlio/factors/plane_extrinsic_factor.h"
#include "rvlio/factors/plane_summary_factor.h"
#include "rvlio/factors/plane_time_offset_factor.h"

namespace rvlio {
namespace {

class SummaryScanFactor final : public ScanFactorKind {
 public:
  std::unique_ptr<ceres::CostFunction> Make(const ScanFactorInput& in) const override {
    auto f = std::make_unique<PlaneSummaryFactor>(in.constraints, in.T_imu_lidar, in.sigma_m,
                                                  in.center_world);
    if (!f->information().allFinite()) return nullptr;
    return f;
  }
  std::vector<double*> Blocks(const ScanFactorBlocks& b) const override { return {b.pose}; }
};

class ExtrinsicScanFactor final : public ScanFactorKind {
 public:
  std::unique_ptr<ceres::CostFunction> Make(const ScanFactorInput& in) const override {
    return std::make_unique<PlaneExtrinsicFactor>(in.constraints, in.sigma_m);
  }
  std::vector<double*> Blocks(const ScanFactorBlocks& b) const override {
    return {b.pose, b.extrinsic};
  }
};

class TimeOffsetScanFactor final : public ScanFactorKind {
 public:
  std::unique_ptr<ceres::CostFunction> Make(const ScanFactorInput& in) const override {
    auto f = std::make_unique<PlaneTimeOffsetFactor>(in.constraints, in.sigma_m, in.T_imu_lidar,
                                                     in.motion, in.td_lin_s, in.center_world);
    if (!f->finite()) return nullptr;
    return f;
  }
  std::vector<double*> Blocks(const ScanFactorBlocks& b) const override {
    return {b.pose, b.speed_bias, b.time_offset};
  }
  // The state's pose moved by the offset's change since the scan was
  // deskewed (ScanTimePose, constraints/time_offset_residual.h).
  Pose3 ScanPose(const ScanPoseInput& in) const override {
    FilterState x;
    x.R_world_imu = in.T_world_imu.R;
    x.p_world_imu = in.T_world_imu.t;
    x.v_world_imu = SpeedBiasBlock::FromArray(in.speed_bias).v_world_imu;
    return ScanTimePose(x, in.motion, in.dtd_s);
  }
};

}  // namespace

std::unique_ptr<ScanFactorKind> MakeScanFactorKind(bool estimate_extrinsics,
                                                   bool estimate_time_offset) {
  if (estimate_time_offset) return std::make_unique<TimeOffsetScanFactor>();
  if (estimate_extrinsics) return std::make_unique<ExtrinsicScanFactor>();
  return std::make_unique<SummaryScanFactor>();
}

}  // namespace rvlio
