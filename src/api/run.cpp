// RunRecording (rvlio/api.h): the odometry over a recording, with the outputs
// of docs/design.md "The command-line contract" when an output folder is given. `rvlio run` is this
// call plus argument parsing, signals and the terminal lines.
#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "rvlio/common/cpu_time.h"
#include "rvlio/api.h"
#include "rvlio/api/result_json.h"
#include "rvlio/config/config_json.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/outputs/deviation_outputs.h"
#include "rvlio/outputs/extrinsic_json.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/formats/reference_map_file.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/formats/tum_stream.h"
#include "rvlio/imu/imu_rate_trajectory.h"

namespace rvlio {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kPartialTrajectory = "trajectory.partial.tum";

nlohmann::json StatsJson(const OdometryStats& o, const SensorReaderStats& r) {
  return {{"scans_received", o.scans_received},
          {"scans_processed", o.scans_processed},
          {"scans_before_imu", o.scans_before_imu},
          {"scans_too_few_points", o.scans_too_few_points},
          {"predict_only", o.predict_only},
          {"diverged_resets", o.diverged_resets},
          {"imu_gaps_over_scan", o.imu_gaps_over_scan},
          {"started_moving", o.started_moving},
          {"imu_factors_skipped", o.imu_factors_skipped},
          {"marginalization_failures", o.marginalization_failures},
          {"scans_out_of_order", o.scans_out_of_order},
          {"scans_stamp_ahead", o.scans_stamp_ahead},
          {"scans_after_imu", o.scans_after_imu},
          {"imu_non_finite", o.imu_non_finite},
          {"time_split_ms",
           {{"association", o.association_ms},
            {"solve", o.solve_ms},
            {"marginalization", o.marginalization_ms}}},
          {"reader", ReaderStatsJson(r)}};
}

int RvActiveScans(const std::vector<ScanResult>& results) {
  int n = 0;
  for (const auto& r : results) n += r.rv.active ? 1 : 0;
  return n;
}

int DegenerateScans(const std::vector<ScanResult>& results) {
  int n = 0;
  for (const auto& r : results) n += r.degeneracy.degenerate ? 1 : 0;
  return n;
}

// With a reference map: where the run left it (scans not localized), as
// spans of consecutive such scans with their length along the trajectory.
nlohmann::json LocalizationJson(const RunArgs& args, const std::vector<ScanResult>& scans) {
  nlohmann::json spans = nlohmann::json::array();
  int localized = 0;
  double longest_m = 0.0, longest_s = 0.0;
  for (size_t i = 0; i < scans.size();) {
    if (scans[i].localized || !scans[i].map_overlap) {
      localized += scans[i].localized ? 1 : 0;
      ++i;
      continue;
    }
    size_t j = i;
    double length_m = 0.0;
    while (j + 1 < scans.size() && !scans[j + 1].localized) {
      length_m += (scans[j + 1].T_world_imu.t - scans[j].T_world_imu.t).norm();
      ++j;
    }
    const double t0 = NsToSeconds(scans[i].t_ns), t1 = NsToSeconds(scans[j].t_ns);
    spans.push_back({{"t_start", t0}, {"t_end", t1}, {"scans", j - i + 1}, {"length_m", length_m}});
    longest_m = std::max(longest_m, length_m);
    longest_s = std::max(longest_s, t1 - t0);
    i = j + 1;
  }
  return {{"map", args.map},
          {"initial_pose", args.initial_pose},
          {"initial_pose_tum", args.initial_pose_tum},
          {"localized_scans", localized},
          {"out_of_map_spans", spans},
          {"longest_out_of_map_m", longest_m},
          {"longest_out_of_map_s", longest_s}};
}

// An odometry result (its local frame) in the user's frame.
void MoveToUserFrame(const LocalOrigin& origin, ScanResult* r) {
  r->T_world_imu.t = origin.ToUser(r->T_world_imu.t);
}

void MoveToUserFrame(const LocalOrigin& origin, std::vector<ScanResult>* scans) {
  for (ScanResult& r : *scans) MoveToUserFrame(origin, &r);
}

struct RunData {
  TimeNs first_ns = -1, last_ns = -1;
  double wall_s = 0.0;
  bool truncated = false;  // the recording was cut short (SensorBagReader::truncated)
};

// The typed figures of the result, which Summary writes.
void SetFigures(const RunData& data, RunResult* result) {
  const TimingStats t = ComputeTimingStats(result->scans);
  const double duration_s = data.first_ns >= 0 ? NsToSeconds(data.last_ns - data.first_ns) : 0.0;
  result->sequence_duration_s = duration_s;
  result->per_scan = t;
  result->wall_s = data.wall_s;
  result->real_time_factor = t.total_ms > 0 ? duration_s / (t.total_ms / 1000.0) : 0.0;
  result->real_time_factor_wall = data.wall_s > 0 ? duration_s / data.wall_s : 0.0;
}

nlohmann::json Summary(const RunArgs& args, const Odometry& odo,
                       const SensorReaderStats& reader_stats, const RunData& data,
                       const RunResult& result) {
  const TimingStats& t = result.per_scan;
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "run";
  j["bag"] = args.bag;
  j["lidar_layout"] = result.lidar_layout;
  j["backend"] = EnumName(args.options.backend);
  j["config"] = ToJson(args.options);
  j["scan_count"] = result.scans.size();
  j["sequence_duration_s"] = result.sequence_duration_s;
  j["per_scan_ms"] = {{"median", t.median_ms}, {"p95", t.p95_ms}, {"max", t.max_ms}};
  j["estimator_total_s"] = t.total_ms / 1000.0;
  j["wall_s"] = result.wall_s;
  j["real_time_factor"] = result.real_time_factor;
  j["real_time_factor_wall"] = result.real_time_factor_wall;
  j["peak_memory_mb"] = PeakMemoryMb();
  j["rv_active_scans"] = RvActiveScans(result.scans);
  j["degenerate_scans"] = DegenerateScans(result.scans);  // by degeneracy.method
  j["stats"] = StatsJson(odo.stats(), reader_stats);
  j["divergence"] = DivergenceJson(odo.divergence());
  if (odo.stats().extrinsic.enabled) j["extrinsic"] = ExtrinsicJson(odo.stats().extrinsic);
  if (odo.stats().time_offset.enabled) j["time_offset"] = TimeOffsetJson(odo.stats().time_offset);
  if (!args.map.empty()) j["localization"] = LocalizationJson(args, result.scans);
  j["warnings"] = result.warnings;
  j["truncated"] = data.truncated;
  j["interrupted"] = result.stopped;
  if (result.stopped) {
    j["signal"] = result.stop_reason;
    j["last_stamp_s"] = result.scans.empty() ? 0.0 : NsToSeconds(result.scans.back().t_ns);
  }
  return j;
}

Status WriteOutputs(const std::string& out_dir, const MapCloud& map,
                    const RunResult& result, const MapDeviation* deviation,
                    const MapLasRequest& las) {
  OutputStage stage(out_dir);
  if (Status s = stage.Open(); !s.ok()) return s;
  if (Status s = WriteTrajectoryOutputs(&stage, result.trajectory, result.imu_trajectory); !s.ok())
    return s;
  if (Status s = WriteMapOutputs(&stage, map, deviation, las); !s.ok()) return s;
  if (Status s = WriteScansCsv(stage.Path("scans.csv"), result.scans, result.rss_mb); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), result.summary_json);
      !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

// Why a run produced no scan at all, naming the topic and the keys to look at
// (nothing is written then, so the counts are in the message).
std::string NoScanMessage(const std::string& bag, const OdometryOptions& o,
                          const SensorReaderStats& r, const OdometryStats& odo) {
  const std::string topic = "lidar.topic '" + o.lidar.topic + "' in " + bag;
  if (r.scans == 0 && r.empty_scans > 0) {
    char range[96];
    std::snprintf(range, sizeof(range), "lidar.min_range %g m, lidar.max_range %g m",
                  o.lidar.min_range, o.lidar.max_range);
    return "every one of the " + std::to_string(r.empty_scans) + " scans on " + topic +
           " is empty after dropping " + std::to_string(r.invalid_points) + " invalid and " +
           std::to_string(r.out_of_range_points) + " out-of-range points (" + range + ")";
  }
  if (r.imu_samples == 0)
    return "no usable IMU sample on imu.topic '" + o.imu.topic + "' in " + bag + " (" +
           std::to_string(r.imu_invalid) + " invalid, " + std::to_string(r.imu_duplicates) +
           " repeated, " + std::to_string(r.imu_non_monotonic) + " out of order)";
  std::string text = "no scan could be processed from " + bag + ": " + std::to_string(r.scans) +
                     " scans read, " + std::to_string(r.scans_before_first_imu) +
                     " before the first IMU sample, " + std::to_string(odo.scans_too_few_points) +
                     " with too few points, " + std::to_string(odo.scans_before_imu) +
                     " during the IMU initialization, " + std::to_string(odo.scans_out_of_order) +
                     " out of order, " + std::to_string(odo.scans_stamp_ahead) +
                     " stamped ahead, " + std::to_string(odo.scans_after_imu) +
                     " after the last IMU sample";
  const int64_t imu_dropped = r.imu_invalid + r.imu_duplicates + r.imu_non_monotonic;
  if (!odo.initialized || imu_dropped > 0)
    text += "; imu.topic '" + o.imu.topic + "' gave " + std::to_string(r.imu_samples) +
            " usable samples" + (odo.initialized ? "" : " (too few for imu.init_duration)") +
            ", " + std::to_string(r.imu_duplicates) + " repeating the previous stamp, " +
            std::to_string(r.imu_non_monotonic) + " out of order, " +
            std::to_string(r.imu_invalid) + " invalid";
  if (o.lidar.time_offset != 0.0) {
    char offset[96];
    std::snprintf(offset, sizeof(offset), "; lidar.time_offset %g s moves every scan", o.lidar.time_offset);
    text += offset;
  }
  return text;
}

// Where the results go as they are estimated.
struct ResultStreams {
  size_t streamed = 0;  // results handed on so far
  TumStream partial;    // trajectory.partial.tum: what a killed run leaves (tum_stream.h)
  std::vector<std::string> warnings;
  // output.imu_trajectory: the IMU-rate trajectory, local frame; fed the IMU
  // samples as read and the results as estimated.
  std::optional<ImuRateTrajectory> imu_rate;
};

// How the IMU-rate poses meet the backend's states (imu/imu_rate_trajectory.h):
// the IESKF's are the filter's own propagation from each update; the
// smoother's states are estimated jointly with the IMU between them.
ImuRateJoin ImuRateJoinOf(Backend backend) {
  return backend == Backend::kIeskf ? ImuRateJoin::kPropagate : ImuRateJoin::kSpread;
}

// Appends the poses of the results not streamed yet to trajectory.partial.tum
// and hands the results to `on_result`, both in the user's frame (the
// estimation's local frame plus `origin`, as trajectory.tum), and to the
// IMU-rate trajectory (local frame); a write error
// stops the streaming with one warning (the run goes on).
void StreamNewPoses(const std::vector<ScanResult>& results, const LocalOrigin& origin,
                    const RunArgs& args, const Odometry& odo, ResultStreams* streams) {
  size_t* streamed = &streams->streamed;
  TumStream* stream = &streams->partial;
  for (; *streamed < results.size(); ++*streamed) {
    if (args.on_result) {
      ScanResult user = results[*streamed];
      MoveToUserFrame(origin, &user);
      args.on_result(user, odo, origin);
    }
    if (streams->imu_rate) streams->imu_rate->AddEstimate(ImuEstimateOf(results[*streamed]));
    if (!stream->is_open()) continue;
    StampedPose pose;
    pose.t_ns = results[*streamed].t_ns;
    pose.p_world_imu = origin.ToUser(results[*streamed].T_world_imu.t);
    pose.q_world_imu = results[*streamed].T_world_imu.quaternion();
    if (Status s = stream->Append(pose); !s.ok())
      streams->warnings.push_back(s.message() + "; the partial trajectory is no longer written");
  }
}

// Reports progress against the time span asked for: the recording's, cut to
// --start / --duration (read once, only when someone listens).
class ProgressReporter {
 public:
  ProgressReporter(const RunArgs& args, Clock::time_point t0) : fn_(args.progress), t0_(t0) {
    if (!fn_ || args.source != nullptr) return;  // a live source has no known span
    StatusOr<BagInfo> info = ReadBagSpan(args.bag);
    if (!info.ok()) return;
    const WindowSpan span = SpanOfWindow(info->start_s, info->end_s, args.window);
    start_s_ = span.first_s;
    end_s_ = span.last_s;
  }
  void Report(int scans, TimeNs t_ns, const DivergenceReport& divergence) const {
    if (!fn_) return;
    RunProgress p;
    p.scans = scans;
    p.fraction = (NsToSeconds(t_ns) - start_s_) / std::max(1e-9, end_s_ - start_s_);
    p.wall_s = SecondsSince(t0_);
    p.divergence = &divergence;
    fn_(p);
  }

 private:
  const std::function<void(const RunProgress&)>& fn_;
  Clock::time_point t0_;
  double start_s_ = 0.0, end_s_ = 1.0;
};

// Feeds the recording to the odometry until its end, a read error or a stop.
void Process(const RunArgs& args, const LocalOrigin& origin, SensorBagReader* reader,
             Odometry* odo, ResultStreams* streams, RunData* data, RunResult* result) {
  const ProgressReporter progress(args, Clock::now());
  ImuSample imu;
  Scan scan;
  TimeNs t = 0;
  for (;;) {
    if (args.stop) {  // the scans done so far are the outputs; pending ones are dropped
      result->stop_reason = args.stop();
      if ((result->stopped = !result->stop_reason.empty())) break;
    }
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    if (!m.ok()) {
      result->read_error = m.status();  // keep what was read: outputs are still written
      break;
    }
    if (*m == SensorMessage::kEnd) break;
    t = *m == SensorMessage::kImu ? imu.t_ns : scan.t_end_ns;
    if (data->first_ns < 0) data->first_ns = t;
    data->last_ns = std::max(data->last_ns, t);
    if (*m == SensorMessage::kImu) {
      odo->AddImu(imu);
      if (streams->imu_rate) streams->imu_rate->AddImu(imu);
    } else {
      odo->AddScan(std::move(scan));
    }
    odo->Poll(&result->scans);
    if (!odo->status().ok()) return;  // the reference map did not fit: nothing is written
    StreamNewPoses(result->scans, origin, args, *odo, streams);
    (void)streams->partial.SyncIfDue();  // a failure surfaces at the next Append
    if (result->rss_mb.size() < result->scans.size())
      result->rss_mb.resize(result->scans.size(), CurrentMemoryMb());
    progress.Report(static_cast<int>(result->scans.size()), t, odo->divergence());
  }
  if (!result->stopped) {
    odo->Finish(&result->scans);
    StreamNewPoses(result->scans, origin, args, *odo, streams);
    progress.Report(static_cast<int>(result->scans.size()), t, odo->divergence());
  }
  result->rss_mb.resize(result->scans.size(), CurrentMemoryMb());
}

// The recording `bag` (null when args.source is given: it is read instead).
StatusOr<std::unique_ptr<SensorBagReader>> OpenReader(const RunArgs& args) {
  if (args.source == nullptr)
    return OpenSensorStream(args.bag, args.options.lidar, args.options.imu, args.window,
                            args.options.io);
  if (args.window.start_s != 0.0 || args.window.duration_s != 0.0)
    return Status::InvalidInput("a time window (--start, --duration) needs a recording");
  return std::unique_ptr<SensorBagReader>();
}

}  // namespace

StatusOr<RunResult> RunRecording(const RunArgs& args) { return RunRecordingAnnotated(args, nullptr); }

StatusOr<RunResult> RunRecordingAnnotated(const RunArgs& in, const SummaryAnnotator& annotate) {
  RunArgs args = in;  // an Ouster recording may supply the default extrinsic
  std::vector<std::string> notes;
  if (args.source == nullptr)
    if (Status s = ApplyRecordingExtrinsics(args.bag, args.options.lidar,
                                            &args.options.extrinsics, &notes);
        !s.ok())
      return s;
  StatusOr<MapLasRequest> las = MapLasRequestOf(args.options.output, args.options.survey);
  if (!las.ok()) return las.status();  // an unknown survey.crs, before anything is read
  Localization localization;
  std::shared_ptr<const ReferenceMap> reference;  // the full cloud, for the deviation
  std::vector<std::string> map_warnings;  // e.g. a float32 map far from zero
  if (!args.map.empty()) {
    StatusOr<Localization> loaded = LoadLocalization(
        args.map, args.initial_pose, args.initial_pose_tum, args.options, &reference, &map_warnings);
    if (!loaded.ok()) return loaded.status();
    localization = std::move(*loaded);
    notes.insert(notes.end(), map_warnings.begin(), map_warnings.end());
  } else if (!args.initial_pose.empty() || !args.initial_pose_tum.empty()) {
    return Status::InvalidInput("--initial-pose and --initial-pose-tum need --map");
  }
  // The odometry runs in the map's local frame; its results go out in the
  // map's frame (without a map the two are the IMU's start frame).
  const LocalOrigin origin = localization.origin;
  StatusOr<std::unique_ptr<Odometry>> odo = Odometry::Create(args.options, std::move(localization));
  if (!odo.ok()) return odo.status();
  StatusOr<std::unique_ptr<SensorBagReader>> opened = OpenReader(args);
  if (!opened.ok()) return opened.status();
  SensorBagReader* reader = args.source != nullptr ? args.source : opened->get();
  const bool write = !args.out_dir.empty();
  OutputFolder out_folder(args.out_dir);  // removed again when nothing gets written
  if (write)
    if (Status s = out_folder.Prepare(); !s.ok()) return s;

  RunResult result;
  RunData data;
  ResultStreams streams;
  TumStream& partial = streams.partial;
  if (write)
    if (Status s =
            partial.Open((std::filesystem::path(args.out_dir) / kPartialTrajectory).string());
        !s.ok())
      streams.warnings.push_back(s.message() + "; the partial trajectory is not written");
  if (args.options.output.imu_trajectory)
    streams.imu_rate.emplace(ImuRateJoinOf(args.options.backend));
  const auto t0 = Clock::now();
  Process(args, origin, reader, odo->get(), &streams, &data, &result);
  data.wall_s = SecondsSince(t0);
  data.truncated = reader->truncated();
  if (!(*odo)->status().ok()) {  // nothing new in the output folder
    if (write) partial.Remove();
    std::string text = "--map " + args.map + ": " + (*odo)->status().message();
    for (const std::string& w : map_warnings) text += "; " + w;  // maybe why the map did not fit
    return Status::InvalidInput(text);
  }

  const SensorReaderStats& reader_stats = reader->stats();
  result.warnings = notes;
  for (const auto& w : ReaderWarnings(reader_stats, args.options.lidar, args.options.imu))
    result.warnings.push_back(w);
  for (const auto& w : (*odo)->warnings()) result.warnings.push_back(w);
  for (const auto& w : reader->warnings()) result.warnings.push_back(w);
  for (const auto& w : streams.warnings) result.warnings.push_back(w);
  result.divergence = (*odo)->divergence();
  result.lidar_layout = reader->lidar_layout();
  if (result.scans.empty()) {  // nothing to write: nothing new in the output folder
    if (write) partial.Remove();
    if (result.stopped) return result;
    if (!result.read_error.ok()) return result.read_error;
    return Status::InvalidInput(
        NoScanMessage(args.bag, args.options, reader_stats, (*odo)->stats()));
  }
  SetFigures(data, &result);
  MapCloud map;  // the output map, when written or compared
  if (write || reference != nullptr || args.on_map) map = (*odo)->MapWithAttributes();
  std::optional<MapDeviation> deviation;  // in the local frame, as the reference
  if (reference != nullptr)
    deviation = ComputeMapDeviation(map.p, *reference, ToTrajectory(result.scans),
                                    args.options.localization.deviation);
  MoveToUserFrame(origin, &result.scans);
  origin.ToUser(&map.p);
  if (args.on_map) args.on_map(map);
  result.trajectory = ToTrajectory(result.scans);
  if (streams.imu_rate) {
    result.imu_trajectory = streams.imu_rate->TakePoses();
    origin.ToUser(&result.imu_trajectory);
  }
  nlohmann::json summary = Summary(args, **odo, reader_stats, data, result);
  summary["local_origin"] = LocalOriginJson(origin);
  if (deviation) summary["localization"]["deviation"] = DeviationSummaryJson(*deviation);
  if (annotate) annotate(&summary);
  result.summary_json = JsonText(summary) + "\n";
  if (!write) return result;
  const Status written =
      WriteOutputs(args.out_dir, map, result, deviation ? &*deviation : nullptr, *las);
  partial.Remove();  // the complete outputs (or the folder as it was) replace it
  if (!written.ok()) return written;  // out_folder removes a folder it created
  out_folder.Keep();
  result.written = true;
  return result;
}

}  // namespace rvlio
