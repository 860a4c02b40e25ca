#pragma once
// The IESKF as a backend of the odometry pipeline (odometry/pipeline.h; the
// paper's system): predict by IMU propagation of the filter, update by the
// iterated point-to-plane update with re-association and RV in every
// iteration (Ieskf::Update, paper Alg. 3), insert the scan at the updated
// state. Copyable: a copy is the whole filter, the snapshot the time
// offset's replay returns to (odometry/ieskf_odometry.h).
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/ieskf/ieskf.h"
#include "rvlio/imu/static_init.h"
#include "rvlio/odometry/options.h"
#include "rvlio/odometry/pipeline.h"

namespace rvlio {

class IeskfBackend {
 public:
  explicit IeskfBackend(const OdometryOptions& options);

  void Initialize(const StaticAlignment& a, const ImuSample& imu, std::deque<ImuSample>* imu_buffer);
  // Propagates with every buffered IMU sample up to the scan end (consumed),
  // then to the scan end itself.
  Prediction Predict(std::deque<ImuSample>* imu_buffer, TimeNs t_end_ns);
  void ChangeWorldFrame(const Pose3& T_ref_world, Prediction* prediction);
  // The first scan without a reference starts the map; every other one is
  // associated and the filter updated (paper Eq. (1), Alg. 3).
  ScanStatus Update(ScanContext& scan, ScanResult* r);
  // The scan at the updated pose into the working map and the output map
  // (the map hold keeps the first moving scans out of the output map).
  void Insert(ScanContext& scan);
  void Finish(ScanContext&) {}

  TimeNs time_ns() const { return filter_.time_ns(); }
  Pose3 T_world_imu() const { return filter_.state().T_world_imu(); }
  Eigen::Vector3d v_world_imu() const { return filter_.state().v_world_imu; }
  Pose3 T_imu_lidar() const { return filter_.state().T_imu_lidar(); }
  double time_offset_s() const { return filter_.time_offset_s(); }
  double time_offset_std_s() const { return filter_.time_offset_std_s(); }
  bool time_offset_at_bound() const { return filter_.time_offset_at_bound(); }
  // Biases, gravity and the posterior's pose covariance (world axes).
  void ReportPropagationState(ScanResult* r) const;
  bool estimates_extrinsics() const { return options_.ieskf.estimate_extrinsics; }
  void CountExcitationScan() { filter_.CountExcitationScan(); }
  const ExtrinsicExcitation& extrinsic_excitation() const { return filter_.extrinsic_excitation(); }
  void AddReports(OdometryStats* stats) const { stats->time_offset.map_hold_scans = map_hold_scans_; }
  std::vector<std::string> Warnings(const OdometryStats&) const { return {}; }

  const Ieskf& filter() const { return filter_; }
  Ieskf& filter() { return filter_; }

 private:
  // Associate -> RV -> Update, iterated inside the filter.
  ScanStatus Correct(ScanContext& scan, ScanResult* r);
  // lidar.estimate_time_offset: true while the first moving scans are
  // provisional in the map, until the offset converges (lidar.time_offset_map_hold).
  bool ProvisionalInMap(TimeNs t_ns, WorkingMap* map);

  OdometryOptions options_;
  Ieskf filter_;
  TimeNs map_hold_start_ns_ = -1;  // the first moving scan's time (-1: none yet)
  bool map_hold_over_ = false;
  std::optional<WorkingMap> map_before_motion_;  // the map at the first moving scan
  int64_t map_hold_scans_ = 0;
  ConstraintList choice_;  // the association that chose the map (reference runs)
};

}  // namespace rvlio
