#include "rvlio/odometry/pipeline.h"

#include <limits>
#include <utility>

#include "rvlio/common/check.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/lidar/deskew.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/odometry/ieskf_backend.h"
#include "rvlio/odometry/smoother_backend.h"

namespace rvlio {
namespace {

// The divergence monitor's options. With lidar.estimate_time_offset the
// rotation check (scans against the gyro) is off: until the offset's estimate
// has converged, that disagreement is what the estimate absorbs, not a wrong
// extrinsic rotation. (The smoother reports no such rotation.)
DivergenceOptions MonitorOptions(const OdometryOptions& options) {
  DivergenceOptions divergence = options.divergence;
  if (options.lidar.estimate_time_offset)
    divergence.max_lidar_rotation_deg = std::numeric_limits<double>::infinity();
  return divergence;
}

}  // namespace

void OutputMapFeed::Hold(TimeNs t_ns, uint32_t scan_index, const Scan& returns) {
  current_t_ns_ = t_ns;
  current_index_ = scan_index;
  current_ = &returns;
}

void OutputMapFeed::Insert(TimeNs t_ns, const std::vector<Eigen::Vector3d>& p_world) {
  while (!held_.empty() && held_.front().t_ns < t_ns) held_.pop_front();
  if (current_ != nullptr && current_t_ns_ == t_ns) {
    map_.InsertScan(p_world, *current_, current_index_);
    current_ = nullptr;
    return;
  }
  RVLIO_CHECK_MSG(!held_.empty() && held_.front().t_ns == t_ns,
                  "odometry: a scan enters the output map without its returns");
  map_.InsertScan(p_world, held_.front().returns, held_.front().scan_index);
  held_.pop_front();
}

void OutputMapFeed::Release() {
  if (current_ != nullptr) held_.push_back({current_t_ns_, current_index_, *current_});
  current_ = nullptr;
}

template <class Backend>
ScanPipeline<Backend>::ScanPipeline(const OdometryOptions& options, Localization localization)
    : options_(options),
      backend_(options),
      map_(options.map, backend_.estimates_extrinsics()),
      output_(options.map.output_resolution),
      preprocessor_(options.lidar),
      T_imu_lidar_prior_(ImuTLidar(options.extrinsics)),
      monitor_(MonitorOptions(options), options.constraints.lidar_noise, options.imu.gravity,
               options.lidar.time_offset_max),
      initializer_(options.imu.init_duration),
      localizer_(std::move(localization), options.localization, options.constraints) {}

template <class Backend>
void ScanPipeline<Backend>::AddImu(const ImuSample& imu) {
  if (!AcceptImu(imu, imu_buffer_, SecondsToNs(options_.imu.max_gap), &stats_)) return;
  scans_.NoteImu(imu.t_ns);
  if (!stats_.initialized) {
    TryInitialize(imu);
    return;
  }
  imu_buffer_.push_back(imu);
}

// Static alignment once imu.init_duration of samples has been collected:
// gravity, gyro bias, zero velocity, identity yaw at the origin.
template <class Backend>
void ScanPipeline<Backend>::TryInitialize(const ImuSample& imu) {
  const std::optional<StaticAlignment> a = initializer_.Add(imu);
  if (!a) return;
  backend_.Initialize(*a, imu, &imu_buffer_);
  stats_.initialized = true;
  stats_.started_moving = a->moving;
  if (a->moving) warnings_.push_back(MovingStartWarning(*a));
}

// The state's time is on the IMU clock, the queued scans' on the reader's
// (before the estimated shift): the state is at the last processed scan's
// end moved by that scan's shift.
template <class Backend>
void ScanPipeline<Backend>::AddScan(Scan scan) {
  scans_.Add(std::move(scan), stats_.initialized, backend_.time_ns() - applied_shift_ns_, &stats_);
}

template <class Backend>
bool ScanPipeline<Backend>::ProcessNext(bool finishing, std::vector<ScanResult>* out) {
  if (!status_.ok() || scans_.empty()) return false;
  if (!finishing && !scans_.FrontReady(imu_buffer_, ScanTimeShiftNs())) return false;
  ProcessFrontScan(out);
  return true;
}

template <class Backend>
void ScanPipeline<Backend>::StartFinishing() {
  scans_.DropPastImu(SecondsToNs(options_.imu.max_gap), &stats_);
}

template <class Backend>
void ScanPipeline<Backend>::Finish() {
  if (finished_ || !stats_.initialized || !status_.ok()) return;
  finished_ = true;
  const Prediction none;
  ScanContext context = Context(backend_.time_ns(), none);
  backend_.Finish(context);
}

template <class Backend>
TimeNs ScanPipeline<Backend>::ScanTimeShiftNs() const {
  if (!options_.lidar.estimate_time_offset) return 0;
  return SecondsToNs(backend_.time_offset_s() - options_.lidar.time_offset);
}

template <class Backend>
void ScanPipeline<Backend>::DropScansBeforeState() {
  scans_.DropStartingBefore(backend_.time_ns() - ScanTimeShiftNs(), &stats_);
}

// One scan, the steps of the method. The scan is first moved onto the IMU
// clock by the current time-offset estimate (prediction and deskew at the
// moved times; the update then refines the estimate); a scan the estimate's
// change since it was queued moved to end at or before the state's time is
// skipped (ScanQueue::PopFrontShifted), so the stamps always increase. The
// result's stamp and pose are the state's: the IMU at the moved scan end.
template <class Backend>
void ScanPipeline<Backend>::ProcessFrontScan(std::vector<ScanResult>* out) {
  const double start_ms = WorkCpuMs();  // association helpers included
  const TimeNs shift_ns = ScanTimeShiftNs();                                           // shift
  std::optional<Scan> scan = scans_.PopFrontShifted(shift_ns, backend_.time_ns(), &stats_);
  if (!scan) return;
  applied_shift_ns_ = shift_ns;
  Prediction prediction = backend_.Predict(&imu_buffer_, scan->t_end_ns);             // predict
  preprocessor_.Downsample(*scan, &downsampled_);                                      // downsample
  if (static_cast<int>(downsampled_.points.size()) < kMinScanPoints) {
    ++stats_.scans_too_few_points;  // the next prediction spans this scan
    return;
  }
  DeskewToScanEnd(*prediction.poses, backend_.T_imu_lidar(), downsampled_.points,     // deskew
                  scan->t_end_ns, &p_lidar_end_);
  if (localizer_.enabled() && !localizer_.started() && !StartInReference(&prediction)) return;
  ScanResult r = NewResult(*scan, prediction);
  ScanContext context = Context(scan->t_end_ns, prediction);
  output_.Hold(scan->t_end_ns, static_cast<uint32_t>(stats_.scans_processed), downsampled_);
  r.status = backend_.Update(context, &r);                                             // associate + update
  backend_.Insert(context);                                                            // insert
  output_.Release();
  Report(scan->t_end_ns, prediction, start_ms, &r);                                    // report
  out->push_back(std::move(r));
}

template <class Backend>
ScanResult ScanPipeline<Backend>::NewResult(const Scan& scan, const Prediction& prediction) const {
  ScanResult r;
  r.degeneracy.method = options_.degeneracy.method;
  r.raw_points = static_cast<int>(scan.points.size());
  r.downsampled_points = static_cast<int>(p_lidar_end_.size());
  r.mean_acc_imu = prediction.mean_imu.acc_imu;
  r.mean_gyro_imu = prediction.mean_imu.gyro_imu;
  return r;
}

template <class Backend>
bool ScanPipeline<Backend>::StartInReference(Prediction* prediction) {
  const ImuKinematics& x = prediction->at_end;
  StatusOr<Pose3> T_ref_world = localizer_.Start(
      x.t_ns, p_lidar_end_, Pose3(x.R_world_imu, x.p_world_imu), backend_.T_imu_lidar());
  if (!T_ref_world.ok()) {
    status_ = T_ref_world.status();
    return false;
  }
  backend_.ChangeWorldFrame(*T_ref_world, prediction);
  return true;
}

template <class Backend>
ScanContext ScanPipeline<Backend>::Context(TimeNs t_ns, const Prediction& prediction) {
  return ScanContext{t_ns, &p_lidar_end_, &prediction, &map_, &output_, &localizer_, &stats_};
}

template <class Backend>
void ScanPipeline<Backend>::Report(TimeNs t_ns, const Prediction& prediction, double start_ms,
                                   ScanResult* r) {
  ReportExtrinsic(r);
  ReportTimeOffset(prediction, r);
  r->t_ns = t_ns;
  r->T_world_imu = backend_.T_world_imu();
  r->v_world_imu = backend_.v_world_imu();
  backend_.ReportPropagationState(r);
  r->ms = WorkCpuMs() - start_ms;
  r->health.divergence_mask = monitor_.Check(HealthSampleOf(*r));
  ++stats_.scans_processed;
}

template <class Backend>
void ScanPipeline<Backend>::ReportExtrinsic(ScanResult* r) {
  if (!backend_.estimates_extrinsics()) return;
  backend_.CountExcitationScan();
  r->T_imu_lidar = backend_.T_imu_lidar();
  stats_.extrinsic =
      MakeExtrinsicReport(backend_.extrinsic_excitation(), T_imu_lidar_prior_, backend_.T_imu_lidar());
  stats_.extrinsic.map_rebuilds = map_.rebuilds();
}

// The excitation is counted with the rate held at the scan's end (the
// prediction's last IMU pose) and the velocity after the update.
template <class Backend>
void ScanPipeline<Backend>::ReportTimeOffset(const Prediction& prediction, ScanResult* r) {
  if (!options_.lidar.estimate_time_offset) return;
  if (!prediction.poses->empty())
    time_offset_excitation_.CountScan(backend_.time_ns(), prediction.poses->back().gyro_imu,
                                      backend_.v_world_imu());
  r->time_offset_s = backend_.time_offset_s();
  r->time_offset_std_s = backend_.time_offset_std_s();
  UpdateTimeOffsetReport(time_offset_excitation_, options_.lidar, backend_.time_offset_s(),
                         backend_.time_offset_std_s(), backend_.time_offset_at_bound(),
                         backend_.time_ns(), &stats_.time_offset);
  stats_.time_offset.replayed_scans = replayed_scans_;
  backend_.AddReports(&stats_);
}

template <class Backend>
std::vector<std::string> ScanPipeline<Backend>::warnings() const {
  std::vector<std::string> w = warnings_;
  for (std::string& s : StatsWarnings(stats_)) w.push_back(std::move(s));
  for (std::string& s : backend_.Warnings(stats_)) w.push_back(std::move(s));
  return w;
}

// The backends (a new one: one line here and one in Odometry::Create).
template class ScanPipeline<IeskfBackend>;
template class ScanPipeline<SmootherBackend>;

}  // namespace rvlio
