// RefineRecording (rvlio/api.h): reads the whole recording into memory
// (downsampled scans and all IMU samples; a chunk job, RefineArgs::chunk,
// only its chunk's scans and the IMU samples around them), batch-refines the initial
// trajectory (refine/refine.h) and, given an output folder, writes
// trajectory.tum, map.pcd and summary.json atomically. `rvlio refine` is this
// call plus argument parsing, signals and the terminal lines.
#include "rvlio/api.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <utility>

#include "rvlio/api/refine_checkpoint.h"
#include "rvlio/api/survey_ties.h"
#include "rvlio/common/cpu_time.h"
#include "rvlio/config/config_json.h"
#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/reference_map_file.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/imu/imu_rate_trajectory.h"
#include "rvlio/lidar/deskew.h"
#include "rvlio/lidar/extrinsics.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/math/pose_interpolation.h"
#include "rvlio/math/so3.h"
#include "rvlio/odometry/reference.h"
#include "rvlio/outputs/deviation_outputs.h"
#include "rvlio/outputs/output_stage.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/outputs/summary_json.h"
#include "rvlio/refine/divergence.h"
#include "rvlio/refine/jobs.h"
#include "rvlio/refine/states.h"

namespace rvlio {
namespace {

using Clock = std::chrono::steady_clock;

RefineConfig ToRefineConfig(const Configuration& o, std::shared_ptr<const VoxelMap> reference,
                            SurveyFactors survey) {
  RefineConfig c;
  c.reference = std::move(reference);
  c.survey = std::move(survey);
  c.imu = o.imu;
  c.T_imu_lidar = ImuTLidar(o.extrinsics);
  c.map = o.map;
  c.constraints = o.constraints;
  c.rv = EffectiveRvOptions(o.rv, o.degeneracy);
  c.degeneracy = o.degeneracy;
  c.refine = o.refine;
  return c;
}

// What `stop` says now ("" goes on).
std::string StopReason(const RefineArgs& args) { return args.stop ? args.stop() : std::string(); }

// IMU samples kept around a chunk job's scans (before its first scan's
// start, after its last scan's end).
constexpr TimeNs kChunkImuMarginNs = 1000000000;  // 1 s

// What the reader saw of the recording's scans (all of them, also those a
// chunk job does not keep): the coverage of the initial trajectory.
struct ScansSeen {
  int64_t scans = 0;
  TimeNs first_end_ns = 0, last_end_ns = 0;
  int64_t outside_init = 0;  // end stamp outside the initial trajectory's span
  int64_t chunk_first = -1, chunk_last = -1;  // recording index (0-based) of a chunk's kept scans
  // The recording's first scan inside the initial trajectory (downsampled),
  // kept by a chunk job too: what refine --map checks the map on.
  std::optional<Scan> first_in_init;
};

// A chunk job keeps the IMU samples around its scans and, as the whole
// refinement, those of the recording's first imu.init_duration (from
// `static_end_ns` on: the static alignment that gives gravity and the gyro
// bias, refine/init.h), so every chunk starts from the same gravity vector.
bool KeepImu(const RefineJobSpan* job, TimeNs static_end_ns, TimeNs t_ns) {
  if (job == nullptr || t_ns <= static_end_ns) return true;
  return (job->chunk == 1 || t_ns >= job->begin_ns - kChunkImuMarginNs) &&
         (job->chunk == job->count || t_ns <= job->end_ns + kChunkImuMarginNs);
}

void CountScan(const Scan& scan, const Trajectory& init, ScansSeen* seen) {
  if (seen->scans == 0) seen->first_end_ns = scan.t_end_ns;
  seen->first_end_ns = std::min(seen->first_end_ns, scan.t_end_ns);
  seen->last_end_ns = std::max(seen->last_end_ns, scan.t_end_ns);
  if (scan.t_end_ns < init.front().t_ns || scan.t_end_ns > init.back().t_ns) ++seen->outside_init;
  ++seen->scans;
}

// Every IMU sample and every scan, downsampled as the odometry does
// (lidar/preprocess.h), so that a 100 s sequence stays small in memory; a
// chunk job (`job`) keeps only its scans and the IMU samples around them.
// Stops early (Ok, *stop_reason set) when `stop` says so.
Status ReadBag(const RefineArgs& args, const RefineJobSpan* job, SensorBagReader* reader,
               RefineInput* input, int64_t* raw_points, ScansSeen* seen,
               std::string* stop_reason, SurveyTies* survey) {
  ScanPreprocessor preprocessor(args.options.lidar);
  ImuSample imu;
  Scan scan;
  TimeNs static_end_ns = 0;
  while ((*stop_reason = StopReason(args)).empty()) {
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    if (!m.ok()) return m.status();
    if (*m == SensorMessage::kEnd) return Status::Ok();
    if (*m == SensorMessage::kImu) {
      if (input->imu.empty()) static_end_ns = imu.t_ns + SecondsToNs(args.options.imu.init_duration);
      if (survey != nullptr) survey->ObserveImu(imu);
      if (KeepImu(job, static_end_ns, imu.t_ns)) input->imu.push_back(imu);
      continue;
    }
    CountScan(scan, input->init, seen);
    const bool in_init = scan.t_start_ns >= input->init.front().t_ns &&
                         scan.t_end_ns <= input->init.back().t_ns;
    if (!seen->first_in_init && in_init) {
      Scan small;
      preprocessor.Downsample(scan, &small);
      if (static_cast<int>(small.points.size()) >= kMinScanPoints) seen->first_in_init = small;
    }
    if (survey != nullptr && survey->NeedsScans()) survey->ObserveScan(scan, input->init);
    if (job != nullptr && !job->Contains(scan.t_end_ns)) continue;
    if (seen->chunk_first < 0) seen->chunk_first = seen->scans - 1;
    seen->chunk_last = seen->scans - 1;
    *raw_points += static_cast<int64_t>(scan.points.size());
    Scan small;
    preprocessor.Downsample(scan, &small);
    input->scans.push_back(std::move(small));
  }
  return Status::Ok();
}

std::string SecondsText(TimeNs t_ns) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", NsToSeconds(t_ns));
  return buf;
}

// Scans the initial trajectory may leave out at the recording's start beyond
// imu.init_duration (the odometry's static initialization has no poses) and
// at its end, before refine says it covers only part of the recording.
constexpr double kCoverageSlackS = 0.5;

// refine --map: how far the initial trajectory may lie from where the scans
// fit the map (CheckMapFits); refine is held to the map from the initial
// poses, so they must be in its frame already (a run --map gives centimetres).
constexpr double kInitInMapM = 0.5;
constexpr double kInitInMapDeg = 5.0;

bool CoversRecording(const ScansSeen& seen, const Trajectory& init, double init_duration_s) {
  if (seen.outside_init == 0) return true;
  const double lead_s = NsToSeconds(init.front().t_ns - seen.first_end_ns);
  const double tail_s = NsToSeconds(seen.last_end_ns - init.back().t_ns);
  return lead_s <= init_duration_s + kCoverageSlackS && tail_s <= kCoverageSlackS;
}

// The warning when the initial trajectory leaves a part of the recording out
// (empty when it covers it, CoversRecording).
std::string CoverageWarning(const ScansSeen& seen, const Trajectory& init,
                            double init_duration_s) {
  if (CoversRecording(seen, init, init_duration_s)) return "";
  return "the initial trajectory (" + SecondsText(init.front().t_ns) + " .. " +
         SecondsText(init.back().t_ns) + " s) covers only part of the recording's scans (" +
         SecondsText(seen.first_end_ns) + " .. " + SecondsText(seen.last_end_ns) + " s): " +
         std::to_string(seen.outside_init) + " of " + std::to_string(seen.scans) +
         " scans outside it are not refined";
}

nlohmann::json CoverageJson(const ScansSeen& seen, const Trajectory& init,
                            double init_duration_s) {
  return {{"init_begin_s", NsToSeconds(init.front().t_ns)},
          {"init_end_s", NsToSeconds(init.back().t_ns)},
          {"scans_begin_s", NsToSeconds(seen.first_end_ns)},
          {"scans_end_s", NsToSeconds(seen.last_end_ns)},
          {"recording_scans", seen.scans},
          {"scans_outside_init", seen.outside_init},
          {"complete", CoversRecording(seen, init, init_duration_s)}};
}

// chunk.json of a chunk job: what `rvlio merge` needs to check and merge it.
nlohmann::json ChunkJson(const RefineArgs& args, const RefineJobSpan& job, const ScansSeen& seen,
                         uint64_t init_hash, uint64_t map_hash, const RefineResult& res) {
  return {{"format", 1},
          {"chunk", job.chunk},
          {"of", job.count},
          {"overlap_s", args.options.refine.job_overlap_s},
          {"core_begin_ns", job.core_begin_ns},
          {"core_end_ns", job.core_end_ns},
          {"begin_ns", job.begin_ns},
          {"end_ns", job.end_ns},
          {"recording_scan_first", seen.chunk_first},
          {"recording_scan_last", seen.chunk_last},
          {"scans_refined", res.trajectory.size()},
          {"t_first_ns", res.trajectory.front().t_ns},
          {"t_last_ns", res.trajectory.back().t_ns},
          {"map_output_resolution", args.options.map.output_resolution},
          {"options_hash", HashText(RefineOptionsHash(args.options))},
          {"init_hash", HashText(init_hash)},
          {"map_hash", args.map.empty() ? std::string() : HashText(map_hash)},
          {"map", args.map},
          {"deviation", DumpYaml(args.options.localization.deviation)},  // for merge --map
          {"interrupted", res.stopped},
          {"bag", args.bag},
          {"init", args.init_path}};
}

std::string ShortChunk(const RefineJobSpan& job, size_t scans) {
  return "--chunk " + std::to_string(job.chunk) + " --of " + std::to_string(job.count) +
         ": the chunk (" + SecondsText(job.begin_ns) + " .. " + SecondsText(job.end_ns) +
         " s) holds " + std::to_string(scans) + " scans, fewer than " +
         std::to_string(kRefineJobMinScans) + "; use fewer chunks";
}

nlohmann::json StatsJson(const RefineStats& s, const SensorReaderStats& r, int64_t raw_points) {
  return {{"scans_input", s.scans_input},
          {"scans_refined", s.scans_refined},
          {"scans_outside_init", s.scans_outside_init},
          {"scans_without_imu", s.scans_without_imu},
          {"scans_too_few_points", s.scans_too_few_points},
          {"scans_out_of_order", s.scans_out_of_order},
          {"imu_samples", s.imu_samples},
          {"raw_points", raw_points},
          {"map_entries", s.map_entries},
          {"chunks", s.chunks},
          {"gravity_from_static", s.gravity_from_static},
          {"started_moving", s.started_moving},
          {"reader", ReaderStatsJson(r)}};
}

struct Times {
  double read_s = 0.0, checkpoint_s = 0.0, wall_s = 0.0;
};

nlohmann::json Summary(const RefineArgs& args, const RefineRunResult& r,
                       const SensorReaderStats& reader_stats, int64_t raw_points,
                       const Times& times) {
  const RefineResult& res = r.refine;
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "refine";
  j["bag"] = args.bag;
  j["init"] = args.init_path;
  if (!args.map.empty()) j["map"] = args.map;
  j["config"] = ToJson(args.options);
  j["linear_solver"] = res.linear_solver;
  j["threads"] = res.threads;
  j["scan_count"] = res.trajectory.size();
  j["sequence_duration_s"] =
      NsToSeconds(res.trajectory.back().t_ns - res.trajectory.front().t_ns);
  j["g_world"] = {res.g_world.x(), res.g_world.y(), res.g_world.z()};
  j["rounds"] = nlohmann::json::array();
  for (const RefineRound& round : res.rounds) j["rounds"].push_back(RoundJson(round));
  // The last round's count, by degeneracy.method (the run's summary has the same key).
  j["degenerate_scans"] = res.rounds.empty() ? 0 : res.rounds.back().degenerate_scans;
  j["converged"] = res.converged;
  j["interrupted"] = res.stopped;
  if (res.stopped) j["signal"] = r.stop_reason;
  j["map_points"] = res.map.size();
  j["time_s"] = {{"read_bag", times.read_s},
                 {"init_solve", res.init_solve_s},
                 {"refine", res.total_s},
                 {"checkpoint", times.checkpoint_s},  // fingerprint + writes (checkpoint_dir)
                 {"wall", times.wall_s}};
  j["peak_memory_mb"] = PeakMemoryMb();
  j["stats"] = StatsJson(res.stats, reader_stats, raw_points);
  j["warnings"] = res.warnings;
  j["divergence"] = DivergenceJson(r.divergence);
  return j;
}

Status WriteOutputs(const std::string& out_dir, const RefineRunResult& r,
                    const MapDeviation* deviation, const MapLasRequest& las) {
  OutputStage stage(out_dir);  // all outputs or none
  if (Status s = stage.Open(); !s.ok()) return s;
  if (!r.chunk_json.empty())
    if (Status s = WriteFileAtomically(stage.Path("chunk.json"), r.chunk_json); !s.ok())
      return stage.Explain(s);
  if (!r.control_csv.empty())
    if (Status s = WriteFileAtomically(stage.Path("control.csv"), r.control_csv); !s.ok())
      return stage.Explain(s);
  if (Status s = WriteTrajectoryOutputs(&stage, r.refine.trajectory, r.imu_trajectory); !s.ok())
    return s;
  if (Status s = WriteMapOutputs(&stage, r.refine.map, deviation, las); !s.ok()) return s;
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), r.summary_json);
      !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

// The refined states (local frame), as the IMU-rate trajectory starts from them.
std::vector<ImuEstimate> RefinedStates(const RefineResult& res) {
  std::vector<ImuEstimate> states(res.trajectory.size());
  for (size_t i = 0; i < states.size(); ++i) {
    ImuEstimate& e = states[i];
    e.state.t_ns = res.trajectory[i].t_ns;
    e.state.R_world_imu = res.trajectory[i].q_world_imu.normalized().toRotationMatrix();
    e.state.p_world_imu = res.trajectory[i].p_world_imu;
    e.state.v_world_imu = res.v_world_imu[i];
    e.bg_imu = res.gyro_bias[i];
    e.ba_imu = res.accel_bias[i];
    e.g_world = res.g_world;
  }
  return states;
}

// The IMU poses over [t0_ns, t1_ns] from the initial trajectory: its poses
// from the last before t0 to the first after t1, each moving at the constant
// velocity and rate that takes it to the next (enough to deskew one scan).
std::vector<ImuPoseSample> PoseSamplesFrom(const Trajectory& init, TimeNs t0_ns, TimeNs t1_ns) {
  size_t first = 0, last = init.size() - 1;
  while (first + 1 < init.size() && init[first + 1].t_ns <= t0_ns) ++first;
  while (last > first + 1 && init[last - 1].t_ns >= t1_ns) --last;
  std::vector<ImuPoseSample> samples;
  for (size_t i = first; i <= last; ++i) {
    ImuPoseSample s;
    s.t_ns = init[i].t_ns;
    s.R_world_imu = init[i].q_world_imu.toRotationMatrix();
    s.p_world_imu = init[i].p_world_imu;
    if (i < last) {
      const double dt_s = NsToSeconds(init[i + 1].t_ns - init[i].t_ns);
      s.v_world_imu = (init[i + 1].p_world_imu - init[i].p_world_imu) / dt_s;
      s.gyro_imu = so3::Log(s.R_world_imu.transpose() * init[i + 1].q_world_imu.toRotationMatrix()) / dt_s;
    }
    samples.push_back(s);
  }
  return samples;
}

// refine --map: the map must fit the recording where the initial trajectory
// puts it, judged as `run --map` judges its start (FindStartInReference):
// the recording's first scan inside the initial trajectory (the same scan for
// every chunk job and the whole refine), deskewed along it, from the
// trajectory's pose there, which must then also be where the scan fits (the
// trajectory in the map's frame). Ok without such a scan (refine says why).
Status CheckMapFits(const RefineArgs& args, const Trajectory& init, const ScansSeen& seen,
                    const VoxelMap& reference, const LocalOrigin& origin) {
  if (!seen.first_in_init) return Status::Ok();
  const Scan* covered = &*seen.first_in_init;
  Pose3 T_ref_imu;
  if (!InterpolatePose(init, covered->t_end_ns, &T_ref_imu)) return Status::Ok();
  const Pose3 T_imu_lidar = ImuTLidar(args.options.extrinsics);
  std::vector<Eigen::Vector3d> p_lidar_end;
  DeskewToScanEnd(PoseSamplesFrom(init, covered->t_start_ns, covered->t_end_ns), T_imu_lidar,
                  covered->points, covered->t_end_ns, &p_lidar_end);
  const std::string start = "the --init pose at " + SecondsText(covered->t_end_ns) + " s";
  StatusOr<ReferenceAlignment> a =
      FindStartInReference(p_lidar_end, T_imu_lidar, reference, &T_ref_imu, T_ref_imu.R,
                           args.options.constraints, args.options.localization, start, origin);
  if (!a.ok()) return Status::InvalidInput("--map " + args.map + ": " + a.status().message());
  const double moved_m = TranslationDifference(a->T_ref_imu, T_ref_imu);
  const double turned_deg = RotationDifferenceDeg(a->T_ref_imu, T_ref_imu);
  if (moved_m > kInitInMapM || turned_deg > kInitInMapDeg) {
    char text[256];
    std::snprintf(text, sizeof(text), ": the scan at %s s fits it %.2f m and %.1f deg away from "
                  "the --init pose there: --init is not in the map's frame",
                  SecondsText(covered->t_end_ns).c_str(), moved_m, turned_deg);
    return Status::InvalidInput("--map " + args.map + text);
  }
  return Status::Ok();
}

// The refinement with its hooks: rounds, checkpoints, the stop flag.
// *checkpoint_s: wall time of the fingerprint and the checkpoint writes.
// map_hash: FileContentHash of --map (0 without one).
// inputs_hash: of --map and --control / the fixes (0 without them).
StatusOr<RefineResult> RefineWithHooks(const RefineArgs& args, RefineInput input,
                                       std::shared_ptr<const VoxelMap> reference,
                                       uint64_t inputs_hash, SurveyFactors survey,
                                       std::string* stop_reason, double* checkpoint_s) {
  RefineHooks hooks;
  hooks.on_round = args.on_round;
  hooks.stop = [&args, stop_reason] { return !(*stop_reason = StopReason(args)).empty(); };
  const bool checkpoints = !args.checkpoint_dir.empty();
  const auto t0 = Clock::now();
  const uint64_t fingerprint = checkpoints ? RefineFingerprint(args.options, input, inputs_hash) : 0;
  *checkpoint_s = checkpoints ? SecondsSince(t0) : 0.0;
  if (checkpoints)
    hooks.on_state = [&args, fingerprint, checkpoint_s](const RefineRoundState& state) {
      const auto t_write = Clock::now();
      Status s = WriteRefineCheckpoint(args.checkpoint_dir, fingerprint, state);
      *checkpoint_s += SecondsSince(t_write);
      return s;
    };
  if (!args.resume)
    return Refine(ToRefineConfig(args.options, std::move(reference), std::move(survey)),
                  std::move(input), hooks);
  StatusOr<RefineRoundState> resume = ReadRefineCheckpoint(args.checkpoint_dir, fingerprint);
  if (!resume.ok()) return resume.status();
  hooks.resume = &*resume;
  if (args.on_resume) args.on_resume(resume->rounds_done);
  return Refine(ToRefineConfig(args.options, std::move(reference), std::move(survey)),
                std::move(input), hooks);
}

// The checkpoint folder: one to resume from must hold a checkpoint; a new
// one is created. Checked before the recording is read.
Status PrepareCheckpointDir(const RefineArgs& args) {
  if (args.checkpoint_dir.empty()) {
    if (args.resume) return Status::InvalidInput("resume needs a checkpoint folder");
    return Status::Ok();
  }
  return args.resume ? CheckpointExists(args.checkpoint_dir)
                     : PrepareOutputDir(args.checkpoint_dir);
}

}  // namespace

StatusOr<RefineRunResult> RefineRecording(const RefineArgs& in) {
  const auto t0 = Clock::now();
  RefineArgs args = in;  // an Ouster recording may supply the default extrinsic
  std::vector<std::string> notes;
  if (Status s = ApplyRecordingExtrinsics(args.bag, args.options.lidar, &args.options.extrinsics,
                                          &notes);
      !s.ok())
    return s;
  StatusOr<MapLasRequest> las = MapLasRequestOf(args.options.output, args.options.survey);
  if (!las.ok()) return las.status();  // an unknown survey.crs, before anything is read
  RefineInput input;
  if (!args.init.empty()) {
    input.init = args.init;
  } else {
    StatusOr<Trajectory> init = ReadTum(args.init_path);
    if (!init.ok()) return init.status();
    input.init = std::move(*init);
  }
  std::optional<RefineJobSpan> job;
  if (args.chunk_count > 0) {
    StatusOr<RefineJobSpan> span =
        MakeRefineJobSpan(input.init.front().t_ns, input.init.back().t_ns, args.chunk,
                          args.chunk_count, args.options.refine.job_overlap_s);
    if (!span.ok()) return span.status();
    job = *span;
  }
  const uint64_t init_hash = job ? TrajectoryHash(input.init) : 0;
  const Trajectory init_span = {input.init.front(), input.init.back()};
  std::shared_ptr<const VoxelMap> reference;
  std::shared_ptr<const ReferenceMap> surface;  // the full cloud, for the deviation
  // The refinement runs in a local frame: the map's (the frame run --map
  // used), else one chosen from the initial trajectory; the outputs go out in
  // the frame of --init and --map.
  LocalOrigin origin = ChooseLocalOrigin(input.init);
  if (!args.map.empty()) {  // read before anything is written
    StatusOr<std::shared_ptr<const VoxelMap>> loaded =
        LoadReferenceMap(args.map, args.options.localization, &surface, &origin, &notes);
    if (!loaded.ok()) return loaded.status();
    reference = std::move(*loaded);
  }
  origin.ToLocal(&input.init);
  uint64_t map_hash = 0;  // what a checkpoint and chunk.json know the map by
  if (!args.map.empty() && (job || !args.checkpoint_dir.empty())) {
    StatusOr<uint64_t> hash = FileContentHash(args.map);
    if (!hash.ok()) return Status::InvalidInput("--map " + hash.status().message());
    map_hash = *hash;
  }
  StatusOr<std::unique_ptr<SurveyTies>> survey = OpenSurveyTies(args.control, args.bag, args.options, origin);
  if (!survey.ok()) return survey.status();  // before anything is written
  const uint64_t inputs_hash =  // the control file and the fixes are inputs of a checkpoint
      *survey == nullptr ? map_hash : (map_hash * 1099511628211ULL) ^ (*survey)->ContentHash();
  if (Status s = PrepareCheckpointDir(args); !s.ok()) return s;
  StatusOr<std::unique_ptr<SensorBagReader>> reader = OpenSensorStream(
      args.bag, args.options.lidar, args.options.imu, args.window, args.options.io);
  if (!reader.ok()) return reader.status();
  const bool write = !args.out_dir.empty();
  OutputFolder out_folder(args.out_dir);  // removed again when nothing gets written
  if (write)
    if (Status s = out_folder.Prepare(); !s.ok()) return s;

  RefineRunResult r;
  int64_t raw_points = 0;
  ScansSeen seen;
  if (Status s = ReadBag(args, job ? &*job : nullptr, reader->get(), &input, &raw_points, &seen,
                         &r.stop_reason, survey->get());
      !s.ok())
    return s;
  if (!r.stop_reason.empty()) {  // stopped while reading: nothing refined or written
    r.stopped = true;
    r.read_complete = false;
    return r;
  }
  if (job && static_cast<int64_t>(input.scans.size()) < kRefineJobMinScans)
    return Status::InvalidInput(ShortChunk(*job, input.scans.size()));
  if (reference != nullptr)
    if (Status s = CheckMapFits(args, input.init, seen, *reference, origin); !s.ok()) return s;
  Times times;
  times.read_s = SecondsSince(t0);
  std::vector<ImuSample> imu_for_output;  // output.imu_trajectory: Refine consumes the input
  if (args.options.output.imu_trajectory) imu_for_output = input.imu;
  SurveyFactors ties;  // in the local survey frame, where refine then runs
  if (*survey != nullptr)
    if (Status s = (*survey)->Prepare(reference != nullptr, &origin, &input.init, &ties); !s.ok())
      return s;
  StatusOr<RefineResult> refined =
      RefineWithHooks(args, std::move(input), std::move(reference), inputs_hash, std::move(ties),
                      &r.stop_reason, &times.checkpoint_s);
  if (!refined.ok()) {
    const std::string what =
        refined.status().message() + " (bag " + args.bag + ", init " + args.init_path + ")";
    return refined.status().WithMessage(what);
  }
  r.refine = std::move(*refined);
  r.refine.warnings.insert(r.refine.warnings.begin(), notes.begin(), notes.end());
  if (std::string w = CoverageWarning(seen, init_span, args.options.imu.init_duration); !w.empty()) r.refine.warnings.push_back(w);
  r.job = job;
  nlohmann::json chunk;  // chunk.json of a chunk job
  if (job) {
    chunk = ChunkJson(args, *job, seen, init_hash, map_hash, r.refine);
    r.chunk_json = JsonText(chunk) + "\n";
  }
  r.stopped = r.refine.stopped;
  if (!r.stopped) r.stop_reason.clear();
  r.divergence = CheckRefineResult(r.refine, args.options.divergence,
                                   args.options.constraints.lidar_noise, args.options.imu.gravity);
  std::optional<MapDeviation> deviation;  // in the local frame, as the reference
  if (surface != nullptr && !r.refine.trajectory.empty())
    deviation = ComputeMapDeviation(r.refine.map.p, *surface, r.refine.trajectory,
                                    args.options.localization.deviation);
  if (*survey != nullptr) DeliverInSurveyFrame(survey->get(), &r);  // residuals, local frame
  if (args.options.output.imu_trajectory) {  // between the refined states, as their IMU factors
    r.imu_trajectory = ImuRatePoses(RefinedStates(r.refine), imu_for_output, ImuRateJoin::kSpread);
    origin.ToUser(&r.imu_trajectory);
  }
  origin.ToUser(&r.refine.trajectory);
  origin.ToUser(&r.refine.map.p);
  times.wall_s = SecondsSince(t0);
  nlohmann::json summary = Summary(args, r, (*reader)->stats(), raw_points, times);
  summary["local_origin"] = LocalOriginJson(origin);
  if (*survey != nullptr) AddSurveySummary(**survey, args.options.survey.crs, &summary);
  summary["truncated"] = (*reader)->truncated();
  summary["init_coverage"] = CoverageJson(seen, init_span, args.options.imu.init_duration);
  if (job) summary["chunk"] = std::move(chunk);
  if (deviation) summary["localization"]["deviation"] = DeviationSummaryJson(*deviation);
  r.summary_json = JsonText(summary) + "\n";
  if (!write) return r;
  if (Status s = WriteOutputs(args.out_dir, r, deviation ? &*deviation : nullptr, *las); !s.ok())
    return s;
  out_folder.Keep();
  r.written = true;
  return r;
}

}  // namespace rvlio
