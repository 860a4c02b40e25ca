// RefineRecording (rvlio/api.h): reads the whole recording into memory
// (downsampled scans and all IMU samples), batch-refines the initial
// trajectory (smoother/refine.h) and, given an output folder, writes
// trajectory.tum, map.pcd and summary.json atomically. `rvlio refine` is this
// call plus argument parsing, signals and the terminal lines.
#include <chrono>
#include <filesystem>
#include <utility>

#include "rvlio/api.h"
#include "rvlio/io/atomic_file.h"
#include "rvlio/io/output_stage.h"
#include "rvlio/io/refine_checkpoint.h"
#include "rvlio/io/run_outputs.h"
#include "rvlio/io/summary_json.h"
#include "rvlio/io/trajectory_io.h"
#include "rvlio/lidar/preprocess.h"

namespace rvlio {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

RefineConfig ToRefineConfig(const OdometryOptions& o) {
  RefineConfig c;
  c.imu = o.imu;
  const auto& e = o.extrinsics.imu_T_lidar;
  c.T_imu_lidar = Pose3(Eigen::Quaterniond(e.rotation_xyzw[3], e.rotation_xyzw[0],
                                           e.rotation_xyzw[1], e.rotation_xyzw[2]),
                        Eigen::Vector3d(e.translation[0], e.translation[1], e.translation[2]));
  c.map = o.map;
  c.constraints = o.constraints;
  c.rv = o.rv;
  c.smoother = o.smoother;
  return c;
}

// What `stop` says now ("" goes on).
std::string StopReason(const RefineArgs& args) { return args.stop ? args.stop() : std::string(); }

// Every IMU sample and every scan, downsampled as the odometry does
// (lidar/preprocess.h), so that a 100 s sequence stays small in memory.
// Stops early (Ok, *stop_reason set) when `stop` says so.
Status ReadBag(const RefineArgs& args, SensorBagReader* reader, RefineInput* input,
               int64_t* raw_points, std::string* stop_reason) {
  ScanPreprocessor preprocessor(args.options.lidar);
  ImuSample imu;
  Scan scan;
  while ((*stop_reason = StopReason(args)).empty()) {
    StatusOr<SensorMessage> m = reader->Next(&imu, &scan);
    if (!m.ok()) return m.status();
    if (*m == SensorMessage::kEnd) return Status::Ok();
    if (*m == SensorMessage::kImu) {
      input->imu.push_back(imu);
      continue;
    }
    *raw_points += static_cast<int64_t>(scan.points.size());
    Scan small;
    preprocessor.Downsample(scan, &small);
    input->scans.push_back(std::move(small));
  }
  return Status::Ok();
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
  j["config"] = ToJson(args.options);
  j["linear_solver"] = res.linear_solver;
  j["threads"] = res.threads;
  j["scan_count"] = res.trajectory.size();
  j["sequence_duration_s"] =
      NsToSeconds(res.trajectory.back().t_ns - res.trajectory.front().t_ns);
  j["g_world"] = {res.g_world.x(), res.g_world.y(), res.g_world.z()};
  j["rounds"] = nlohmann::json::array();
  for (const RefineRound& round : res.rounds) j["rounds"].push_back(RoundJson(round));
  j["converged"] = res.converged;
  j["interrupted"] = res.stopped;
  if (res.stopped) j["signal"] = r.stop_reason;
  j["map_points"] = res.map_points.size();
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

Status WriteOutputs(const std::string& out_dir, const RefineRunResult& r) {
  OutputStage stage(out_dir);  // all outputs or none
  if (Status s = stage.Open(); !s.ok()) return s;
  if (Status s = WriteTum(stage.Path("trajectory.tum"), r.refine.trajectory); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteMapPcd(stage.Path("map.pcd"), r.refine.map_points); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), JsonText(r.summary) + "\n");
      !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

// The refinement with its hooks: rounds, checkpoints, the stop flag.
// *checkpoint_s: wall time of the fingerprint and the checkpoint writes.
StatusOr<RefineResult> RefineWithHooks(const RefineArgs& args, RefineInput input,
                                       std::string* stop_reason, double* checkpoint_s) {
  RefineHooks hooks;
  hooks.on_round = args.on_round;
  hooks.stop = [&args, stop_reason] { return !(*stop_reason = StopReason(args)).empty(); };
  const bool checkpoints = !args.checkpoint_dir.empty();
  const auto t0 = Clock::now();
  const uint64_t fingerprint = checkpoints ? RefineFingerprint(args.options, input) : 0;
  *checkpoint_s = checkpoints ? SecondsSince(t0) : 0.0;
  if (checkpoints)
    hooks.on_state = [&args, fingerprint, checkpoint_s](const RefineRoundState& state) {
      const auto t_write = Clock::now();
      Status s = WriteRefineCheckpoint(args.checkpoint_dir, fingerprint, state);
      *checkpoint_s += SecondsSince(t_write);
      return s;
    };
  if (!args.resume) return Refine(ToRefineConfig(args.options), std::move(input), hooks);
  StatusOr<RefineRoundState> resume = ReadRefineCheckpoint(args.checkpoint_dir, fingerprint);
  if (!resume.ok()) return resume.status();
  hooks.resume = &*resume;
  if (args.on_resume) args.on_resume(resume->rounds_done);
  return Refine(ToRefineConfig(args.options), std::move(input), hooks);
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

StatusOr<RefineRunResult> RefineRecording(const RefineArgs& args) {
  const auto t0 = Clock::now();
  RefineInput input;
  if (!args.init.empty()) {
    input.init = args.init;
  } else {
    StatusOr<Trajectory> init = ReadTum(args.init_path);
    if (!init.ok()) return init.status();
    input.init = std::move(*init);
  }
  if (Status s = PrepareCheckpointDir(args); !s.ok()) return s;
  StatusOr<std::unique_ptr<SensorBagReader>> reader = OpenSensorStream(
      args.bag, args.options.lidar, args.options.imu, args.window, args.options.io);
  if (!reader.ok()) return reader.status();
  const bool write = !args.out_dir.empty();
  if (write)
    if (Status s = PrepareOutputDir(args.out_dir); !s.ok()) return s;

  RefineRunResult r;
  int64_t raw_points = 0;
  if (Status s = ReadBag(args, reader->get(), &input, &raw_points, &r.stop_reason); !s.ok())
    return s;
  if (!r.stop_reason.empty()) {  // stopped while reading: nothing refined or written
    r.stopped = true;
    r.read_complete = false;
    return r;
  }
  Times times;
  times.read_s = SecondsSince(t0);
  StatusOr<RefineResult> refined =
      RefineWithHooks(args, std::move(input), &r.stop_reason, &times.checkpoint_s);
  if (!refined.ok()) {
    const std::string what =
        refined.status().message() + " (bag " + args.bag + ", init " + args.init_path + ")";
    return refined.status().code() == StatusCode::kInternal ? Status::Internal(what)
                                                            : Status::InvalidInput(what);
  }
  r.refine = std::move(*refined);
  r.stopped = r.refine.stopped;
  if (!r.stopped) r.stop_reason.clear();
  r.divergence = CheckRefineResult(r.refine, args.options.divergence,
                                   args.options.constraints.lidar_noise, args.options.imu.gravity);
  times.wall_s = SecondsSince(t0);
  r.summary = Summary(args, r, (*reader)->stats(), raw_points, times);
  if (!write) return r;
  if (Status s = WriteOutputs(args.out_dir, r); !s.ok()) return s;
  r.written = true;
  return r;
}

}  // namespace rvlio
