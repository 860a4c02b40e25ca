// `rvlio refine`: reads the whole bag into memory (downsampled scans and all
// IMU samples), batch-refines the initial trajectory (smoother/refine.h) and
// writes trajectory.tum, map.pcd and summary.json atomically.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <utility>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "json_text.h"
#include "commands.h"
#include "common_options.h"
#include "interrupt.h"
#include "refine_checkpoint.h"
#include "divergence_cli.h"
#include "run_pipeline.h"
#include "window_options.h"
#include "rvlio/io/atomic_file.h"
#include "rvlio/io/config.h"
#include "rvlio/io/run_outputs.h"
#include "rvlio/io/sensor_bag.h"
#include "rvlio/io/trajectory_io.h"
#include "rvlio/lidar/preprocess.h"
#include "rvlio/smoother/refine.h"

namespace rvlio::cli {
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

// Every IMU sample and every scan, downsampled as the odometry does
// (lidar/preprocess.h), so that a 100 s sequence stays small in memory.
// Stops early (Ok) when interrupted.
Status ReadBag(SensorBagReader* reader, const LidarOptions& lidar, RefineInput* input,
               int64_t* raw_points) {
  ScanPreprocessor preprocessor(lidar);
  ImuSample imu;
  Scan scan;
  while (!Interrupted()) {
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

void PrintRound(const RefineRound& r, int rounds) {
  std::printf(
      "rvlio refine: round %d/%d: cost %.6g -> %.6g, %d iterations, max change %.4f m %.4f deg, "
      "%lld constraints, %d RV-active scans, %.1f s (deskew %.1f, map %.1f, associate %.1f, "
      "solve %.1f)\n",
      r.round, rounds, r.cost_before, r.cost_after, r.iterations, r.max_translation_change_m,
      r.max_rotation_change_deg, static_cast<long long>(r.constraints), r.rv_active_scans,
      r.total_s, r.deskew_s, r.map_s, r.associate_s, r.solve_s);
  std::fflush(stdout);
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

struct Request {
  std::string bag, init, out_dir;
  std::string checkpoint_dir;  // --checkpoint, or --resume's folder
  bool resume = false;
};

struct AppTimes {
  double read_s = 0.0, checkpoint_s = 0.0, wall_s = 0.0;
};

Status WriteOutputs(const Request& req, const OdometryOptions& options, const RefineResult& res,
                    const DivergenceReport& divergence, const SensorReaderStats& reader_stats,
                    int64_t raw_points, const AppTimes& times) {
  OutputStage stage(req.out_dir);  // all outputs or none (run_pipeline.h)
  if (Status s = stage.Open(); !s.ok()) return s;
  if (Status s = WriteTum(stage.Path("trajectory.tum"), res.trajectory); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteMapPcd(stage.Path("map.pcd"), res.map_points); !s.ok())
    return stage.Explain(s);
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "refine";
  j["bag"] = req.bag;
  j["init"] = req.init;
  j["config"] = ToJson(options);
  j["linear_solver"] = res.linear_solver;
  j["threads"] = res.threads;
  j["scan_count"] = res.trajectory.size();
  j["sequence_duration_s"] =
      NsToSeconds(res.trajectory.back().t_ns - res.trajectory.front().t_ns);
  j["g_world"] = {res.g_world.x(), res.g_world.y(), res.g_world.z()};
  j["rounds"] = nlohmann::json::array();
  for (const RefineRound& r : res.rounds) j["rounds"].push_back(RoundJson(r));
  j["converged"] = res.converged;
  j["interrupted"] = res.stopped;
  if (res.stopped) j["signal"] = InterruptSignalName();
  j["map_points"] = res.map_points.size();
  j["time_s"] = {{"read_bag", times.read_s},
                 {"init_solve", res.init_solve_s},
                 {"refine", res.total_s},
                 {"checkpoint", times.checkpoint_s},  // fingerprint + writes (--checkpoint)
                 {"wall", times.wall_s}};
  j["peak_memory_mb"] = PeakMemoryMb();
  j["stats"] = StatsJson(res.stats, reader_stats, raw_points);
  j["warnings"] = res.warnings;
  j["divergence"] = DivergenceJson(divergence);
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), JsonText(j) + "\n"); !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

}  // namespace

namespace {

// The refinement with its hooks: round lines, checkpoints, the interrupt flag.
// *checkpoint_s: wall time of the fingerprint and the checkpoint writes.
StatusOr<RefineResult> RefineWithHooks(const Request& req, const OdometryOptions& options,
                                       RefineInput input, double* checkpoint_s) {
  const int rounds = options.smoother.refine_rounds;
  RefineHooks hooks;
  hooks.on_round = [rounds](const RefineRound& r) { PrintRound(r, rounds); };
  hooks.stop = [] { return Interrupted(); };
  const auto t0 = Clock::now();
  const uint64_t fingerprint =
      req.checkpoint_dir.empty() ? 0 : RefineFingerprint(options, input);
  *checkpoint_s = req.checkpoint_dir.empty() ? 0.0 : SecondsSince(t0);
  if (!req.checkpoint_dir.empty())
    hooks.on_state = [&req, fingerprint, checkpoint_s](const RefineRoundState& state) {
      const auto t_write = Clock::now();
      Status s = WriteRefineCheckpoint(req.checkpoint_dir, fingerprint, state);
      *checkpoint_s += SecondsSince(t_write);
      return s;
    };
  if (!req.resume) return Refine(ToRefineConfig(options), std::move(input), hooks);
  StatusOr<RefineRoundState> resume = ReadRefineCheckpoint(req.checkpoint_dir, fingerprint);
  if (!resume.ok()) return resume.status();
  hooks.resume = &*resume;
  std::printf("rvlio refine: resuming after round %d from %s\n", resume->rounds_done,
              req.checkpoint_dir.c_str());
  return Refine(ToRefineConfig(options), std::move(input), hooks);
}

// --checkpoint DIR / --resume DIR (the same folder goes on receiving checkpoints).
int ReadCheckpointArgs(const Args& args, Request* req) {
  if (args.Has("checkpoint") && args.Has("resume") &&
      args.Get("checkpoint") != args.Get("resume"))
    return Fail("refine", "--resume " + args.Get("resume") + " goes on checkpointing there; "
                "--checkpoint " + args.Get("checkpoint") + " names another folder");
  req->resume = args.Has("resume");
  req->checkpoint_dir = req->resume ? args.Get("resume") : args.Get("checkpoint");
  if (req->resume) {
    if (Status s = CheckpointExists(req->checkpoint_dir); !s.ok())
      return Fail("refine", s.message());
  } else if (!req->checkpoint_dir.empty() && !PrepareOutputDir("refine", req->checkpoint_dir)) {
    return 2;
  }
  return 0;
}

}  // namespace

int CmdRefine(int argc, char** argv) {
  CommandSpec spec{"refine",
                   "Batch-refines a whole sequence starting from a previous run's trajectory "
                   "(all scans, IMU factors, re-association rounds; sparse Cholesky) and writes "
                   "trajectory.tum, map.pcd and summary.json to the output folder. SIGINT/SIGTERM "
                   "write the last completed round's result and exit 130/143.",
                   {{"bag", "PATH", "recording with LiDAR and IMU topics: ROS1 .bag, ROS 2 .db3, .mcap or bag folder", true},
                    {"init", "TUM", "initial trajectory (TUM format), e.g. rvlio run's", true},
                    ConfigOption(),
                    SetOption(),
                    {"out", "DIR", "output folder", true},
                    {"checkpoint", "DIR",
                     "after each round, write the state to continue from to DIR/refine.checkpoint"},
                    {"resume", "DIR",
                     "continue from DIR/refine.checkpoint (same --bag, --init, --config and --set; "
                     "smoother.refine_rounds may differ) and go on checkpointing there"},
                    AllowDivergenceOption(),
                    StartOption(),
                    DurationOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  InterruptScope interrupt_scope;
  ReadWindow window;
  if (std::string err = ParseWindow(args, &window); !err.empty()) return Fail("refine", err);
  const auto t0 = Clock::now();
  Request req;
  req.bag = args.Get("bag");
  req.init = args.Get("init");
  req.out_dir = args.Get("out");
  std::vector<std::string> config_warnings;
  StatusOr<OdometryOptions> options =
      LoadConfig(args.GetAll("config"), args.GetAll("set"), &config_warnings);
  if (!options.ok()) return Fail("refine", options.status().message());
  for (const auto& w : config_warnings)
    std::fprintf(stderr, "rvlio refine: warning: %s\n", w.c_str());
  StatusOr<Trajectory> init = ReadTum(req.init);
  if (!init.ok()) return Fail("refine", "--init: " + init.status().message());
  if (int rc = ReadCheckpointArgs(args, &req); rc != 0) return rc;
  StatusOr<std::unique_ptr<SensorBagReader>> reader =
      OpenSensorStream(req.bag, options->lidar, options->imu, window, options->io);
  if (!reader.ok()) return Fail("refine", reader.status().message());
  if (!PrepareOutputDir("refine", req.out_dir)) return 2;

  RefineInput input;
  input.init = std::move(*init);
  int64_t raw_points = 0;
  if (Status s = ReadBag(reader->get(), options->lidar, &input, &raw_points); !s.ok())
    return Fail("refine", s.message());
  if (Interrupted()) {
    std::fprintf(stderr, "rvlio refine: interrupted by %s while reading the bag; nothing written\n",
                 InterruptSignalName().c_str());
    return InterruptExitCode();
  }
  const double read_s = SecondsSince(t0);
  double checkpoint_s = 0.0;
  StatusOr<RefineResult> result = RefineWithHooks(req, *options, std::move(input), &checkpoint_s);
  if (!result.ok())
    return Fail("refine", result.status().message() + " (bag " + req.bag + ", init " + req.init + ")",
                result.status().exit_code());
  const DivergenceReport divergence = CheckRefineResult(
      *result, options->divergence, options->constraints.lidar_noise, options->imu.gravity);
  const Status written = WriteOutputs(req, *options, *result, divergence, (*reader)->stats(),
                                      raw_points, {read_s, checkpoint_s, SecondsSince(t0)});
  for (const auto& w : result->warnings) std::fprintf(stderr, "rvlio refine: warning: %s\n", w.c_str());
  size_t warned = 0;
  WarnDivergence("refine", divergence, &warned);
  if (!written.ok()) return Fail("refine", written.message(), written.exit_code());
  if (result->stopped) {
    std::fprintf(stderr, "rvlio refine: interrupted by %s: wrote the result after round %zu "
                 "(trajectory.tum, map.pcd, summary.json) to %s\n", InterruptSignalName().c_str(),
                 result->rounds.empty() ? size_t{0} : static_cast<size_t>(result->rounds.back().round),
                 req.out_dir.c_str());
    return InterruptExitCode();
  }
  std::printf("rvlio refine: %zu scans, %zu rounds%s, %s, %.1f s, peak memory %.0f MB -> %s\n",
              result->trajectory.size(), result->rounds.size(),
              result->converged ? " (converged)" : "", result->linear_solver.c_str(),
              SecondsSince(t0), PeakMemoryMb(), req.out_dir.c_str());
  if (divergence.detected)
    return FinishDiverged("refine", divergence, req.out_dir, args.Has("allow-divergence"));
  return 0;
}

}  // namespace rvlio::cli
