#include "rvlio/experiments/compare.h"

#include <chrono>
#include <cmath>
#include <utility>

#include "rvlio/common/cpu_time.h"
#include "rvlio/config/config.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/formats/point_cloud_file.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/trajectory_io.h"
#include "rvlio/outputs/run_outputs.h"

namespace rvlio::experiments {
namespace {

using Clock = std::chrono::steady_clock;

// The configurations of one request, loaded once: the request's (refine's)
// and each variant's (the request's with the variant's overrides on top).
struct Configurations {
  Configuration base;
  std::vector<Configuration> variants;  // parallel to StandardVariants()
};

// What every row is evaluated against.
struct Truth {
  Trajectory trajectory;
  std::vector<Eigen::Vector3d> ref_map;  // empty without ref_map
};

void Warn(const CompareRequest& req, const std::string& step, const std::string& what) {
  if (req.on_warning) req.on_warning(step + ": " + what);
}

StatusOr<Configurations> LoadConfigurations(const CompareRequest& req) {
  std::vector<std::string> deprecations;
  StatusOr<Configuration> base = LoadConfig(req.config_files, req.overrides, &deprecations);
  if (!base.ok()) return base.status();
  for (const std::string& w : deprecations) Warn(req, "config", w);
  Configurations c;
  c.base = *base;
  for (const CompareVariant& v : StandardVariants()) {
    Configuration options = c.base;
    for (const std::string& o : v.overrides)
      if (Status s = ApplyOverride(options, o); !s.ok())
        return Status::InvalidInput("variant " + v.name + ": " + s.message());
    if (Status s = options.Validate(); !s.ok())
      return Status::InvalidInput("variant " + v.name + ": " + s.message());
    c.variants.push_back(std::move(options));
  }
  return c;
}

StatusOr<Truth> LoadTruth(const CompareRequest& req) {
  Truth truth;
  StatusOr<Trajectory> gt = ReadTrajectory(req.gt);
  if (!gt.ok()) return Status::InvalidInput("--gt: " + gt.status().message());
  if (gt->size() < 3)
    return Status::InvalidInput("--gt: " + req.gt + " has " + std::to_string(gt->size()) +
                                " poses; at least 3 are needed to align and evaluate");
  truth.trajectory = std::move(*gt);
  if (!req.ref_map.empty()) {
    StatusOr<PointCloudFile> ref = ReadPointCloud(req.ref_map, PointCloudReadOptions{false});
    if (!ref.ok()) return Status::InvalidInput("--ref-map: " + ref.status().message());
    truth.ref_map = std::move(ref->points);
  }
  return truth;
}

// The recording opens with the request's topics (only the checks at open).
Status CheckRecording(const CompareRequest& req, const Configuration& options) {
  ReaderOptions inline_io = options.io;
  inline_io.reader_thread = false;  // read nothing ahead
  StatusOr<std::unique_ptr<SensorBagReader>> reader =
      OpenSensorStream(req.bag, options.lidar, options.imu, req.window, inline_io);
  return reader.ok() ? Status::Ok() : reader.status();
}

std::string StepDir(const CompareRequest& req, const std::string& name) {
  return req.out_dir + "/" + name;
}

// The step's map, as its map.pcd stores it, against the reference cloud, as
// `rvlio eval --map`, after moving it into the ground truth's frame by the
// alignment of the run's poses (eval->T_ref_est_poses: the estimate's world
// frame is its own, and a small initial tilt moves far walls by centimetres;
// the ATE's Umeyama alignment of positions leaves the roll about a straight
// path free). A failure is a warning and leaves the row's map figures empty.
void EvaluateRowMap(const CompareRequest& req, const Truth& truth,
                    std::vector<Eigen::Vector3d> map_points, CompareRow* row) {
  if (truth.ref_map.empty() || !row->eval) return;
  map_points = MapPointsAsStored(std::move(map_points));
  for (Eigen::Vector3d& p : map_points) p = row->eval->T_ref_est_poses * p;
  StatusOr<MapEvalResult> m = EvaluateMap(map_points, truth.ref_map, MapEvalOptions());
  if (!m.ok()) {
    Warn(req, row->name, "map evaluation: " + m.status().message());
    return;
  }
  row->map_eval = std::move(*m);
}

// Evaluates the estimate as its trajectory.tum holds it (the figures equal
// `rvlio eval` on that file).
void EvaluateRow(const CompareRequest& req, const Truth& truth, const Trajectory& estimate,
                 std::vector<Eigen::Vector3d> map_points, CompareRow* row) {
  StatusOr<Trajectory> written =
      RoundTripTum(estimate, StepDir(req, row->name) + "/trajectory.tum");
  if (written.ok()) row->trajectory = std::move(*written);
  StatusOr<EvalResult> e = written.ok() ? Evaluate(truth.trajectory, row->trajectory, EvalOptions())
                                        : StatusOr<EvalResult>(written.status());
  if (!e.ok()) {
    row->exit_code = ExitStatus(e.status().code());
    row->eval_error = "evaluation: " + e.status().message();
    Warn(req, row->name, row->eval_error);
    return;
  }
  row->eval = std::move(*e);
  EvaluateRowMap(req, truth, std::move(map_points), row);
}

int StopExitCode(const CompareRequest& req) {
  return req.stop_exit_code ? req.stop_exit_code() : 1;
}

void MarkFailed(const CompareRequest& req, Status error, CompareRow* row) {
  row->exit_code = ExitStatus(error.code());
  Warn(req, row->name, error.message());
  row->run_error = std::move(error);
}

void MarkInterrupted(const CompareRequest& req, CompareRow* row) {
  row->interrupted = true;
  row->exit_code = StopExitCode(req);
}

// Runs `call` (a library call giving a StatusOr) timed into `row`: a failed
// row, or the result handed to `take`.
template <class Call, class Take>
CompareRow TimedStep(const CompareRequest& req, CompareRow row, Call call, Take take) {
  const auto t0 = Clock::now();
  auto result = call();
  row.wall_s = SecondsSince(t0);
  if (!result.ok())
    MarkFailed(req, result.status(), &row);
  else
    take(*result, &row);
  return row;
}

// Fills `row` from a finished run (the command `rvlio run` with
// --allow-divergence would have exited 0, or 2 after a read error).
void TakeRunResult(const CompareRequest& req, const Truth& truth, const RunResult& r,
                   std::vector<Eigen::Vector3d> map_points, CompareRow* row) {
  if (r.scans.empty() || r.stopped) return MarkInterrupted(req, row);
  for (const std::string& w : r.warnings) Warn(req, row->name, w);
  if (!r.read_error.ok())
    return MarkFailed(
        req,
        Status::InvalidInput(r.read_error.message() + " (outputs hold the scans read before it)"),
        row);
  row->scans = static_cast<int>(r.scans.size());
  row->ms_per_scan = r.per_scan.median_ms;
  row->real_time_factor = r.real_time_factor;
  row->diverged = r.divergence.detected;
  EvaluateRow(req, truth, r.trajectory, std::move(map_points), row);
}

CompareRow RunVariant(const CompareRequest& req, CompareRow row, const Configuration& options,
                      const Truth& truth) {
  RunArgs run;
  run.bag = req.bag;
  run.options = options;
  run.out_dir = StepDir(req, row.name);
  run.window = req.window;
  run.stop = req.stop;
  run.progress = req.on_run_progress;
  std::vector<Eigen::Vector3d> map_points;  // for the map figures only
  if (!truth.ref_map.empty()) run.on_map = [&map_points](const MapCloud& m) { map_points = m.p; };
  return TimedStep(
      req, std::move(row), [&] { return RunRecording(run); },
      [&](const RunResult& r, CompareRow* out) {
        TakeRunResult(req, truth, r, std::move(map_points), out);
      });
}

void TakeRefineResult(const CompareRequest& req, const Truth& truth, const RefineRunResult& r,
                      CompareRow* row) {
  if (!r.read_complete || r.stopped) return MarkInterrupted(req, row);
  if (req.on_refine_result) req.on_refine_result(r);
  const RefineResult& refined = r.refine;
  for (const std::string& w : refined.warnings) Warn(req, row->name, w);
  row->scans = static_cast<int>(refined.trajectory.size());
  if (row->scans > 0 && refined.total_s > 0)
    row->ms_per_scan = 1000.0 * refined.total_s / row->scans;
  const double duration_s =
      NsToSeconds(refined.trajectory.back().t_ns - refined.trajectory.front().t_ns);
  if (refined.total_s > 0) row->real_time_factor = duration_s / refined.total_s;
  row->diverged = r.divergence.detected;
  EvaluateRow(req, truth, refined.trajectory,
              truth.ref_map.empty() ? std::vector<Eigen::Vector3d>() : refined.map.p, row);
}

CompareRow RunRefine(const CompareRequest& req, CompareRow row, const CompareRow& start,
                     const Configuration& options, const Truth& truth) {
  RefineArgs refine;
  refine.bag = req.bag;
  refine.init_path = StepDir(req, start.name) + "/trajectory.tum";  // summary.json "init"
  refine.init = start.trajectory;                                   // as that file holds it
  refine.options = options;
  refine.out_dir = StepDir(req, kRefineStep);
  refine.window = req.window;
  refine.stop = req.stop;
  if (req.on_refine_round)
    refine.on_round = [&req, rounds = options.refine.rounds](const RefineRound& r) {
      req.on_refine_round(r, rounds);
    };
  return TimedStep(
      req, std::move(row), [&] { return RefineRecording(refine); },
      [&](const RefineRunResult& r, CompareRow* out) { TakeRefineResult(req, truth, r, out); });
}

bool Stopped(const CompareRequest& req) { return req.stop && !req.stop().empty(); }

// Runs one step between its two progress calls; after a stop the step is
// marked interrupted without running.
template <class RunStep>
void Step(const CompareRequest& req, CompareRow head, RunStep run, CompareResult* result) {
  CompareStep step{static_cast<int>(result->rows.size()), CompareSteps(req), false, &head};
  if (result->interrupted || Stopped(req)) {
    MarkInterrupted(req, &head);
    result->rows.push_back(std::move(head));
  } else {
    if (req.on_step) req.on_step(step);
    result->rows.push_back(run(std::move(head)));
  }
  result->interrupted = result->interrupted || result->rows.back().interrupted;
  step.finished = true;
  step.row = &result->rows.back();
  if (req.on_step) req.on_step(step);
}

CompareRow Head(const std::string& name, const std::string& label,
                const std::vector<std::string>& overrides = {}, const std::string& init = "") {
  CompareRow row;
  row.name = name;
  row.label = label;
  row.overrides = overrides;
  row.init = init;
  return row;
}

}  // namespace

const std::vector<CompareVariant>& StandardVariants() {
  static const std::vector<CompareVariant> kVariants = {
      {"ieskf_rv_off", "IESKF, RV off", {"backend=ieskf", "rv.enabled=false"}},
      {"ieskf_rv_on", "IESKF, RV on (RV-LIO)", {"backend=ieskf", "rv.enabled=true"}},
      {"smoother_rv_off", "smoother, RV off", {"backend=smoother", "rv.enabled=false"}},
      {"smoother_rv_on", "smoother, RV on", {"backend=smoother", "rv.enabled=true"}}};
  return kVariants;
}

int CompareSteps(const CompareRequest& request) {
  return static_cast<int>(StandardVariants().size()) + (request.refine ? 1 : 0);
}

int ExitStatus(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return 0;
    case StatusCode::kInvalidInput:
      return 2;
    case StatusCode::kIoError:
      return 2;
    case StatusCode::kInternal:
      return 1;
  }
  return 1;  // not reached: every code is listed above
}

const char* CompareRow::StatusName() const {
  return interrupted ? "interrupted" : ok() ? "ok" : (measured() ? "diverged" : "failed");
}

const CompareRow* CompareResult::Best() const {
  const CompareRow* best = nullptr;
  for (const CompareRow& r : rows)
    if (r.ok() && (!best || r.eval->ape_m.rmse < best->eval->ape_m.rmse)) best = &r;
  return best;
}

int CompareResult::Diverged() const {
  int n = 0;
  for (const CompareRow& r : rows) n += r.diverged ? 1 : 0;
  return n;
}

StatusOr<CompareResult> RunCompare(const CompareRequest& req) {
  StatusOr<Configurations> configs = LoadConfigurations(req);
  if (!configs.ok()) return configs.status();
  StatusOr<Truth> truth = LoadTruth(req);
  if (!truth.ok()) return truth.status();
  if (Status s = CheckRecording(req, configs->base); !s.ok()) return s;
  CompareResult result;
  result.rows.reserve(CompareSteps(req));  // steps keep pointers to rows
  const std::vector<CompareVariant>& variants = StandardVariants();
  for (size_t i = 0; i < variants.size(); ++i) {
    const CompareVariant& v = variants[i];
    Step(
        req, Head(v.name, v.label, v.overrides),
        [&](CompareRow row) {
          return RunVariant(req, std::move(row), configs->variants[i], *truth);
        },
        &result);
  }
  const CompareRow* best = result.Best();
  if (req.refine && result.interrupted) {
    Step(
        req, Head(kRefineStep, kRefineStep), [](CompareRow row) { return row; }, &result);
  } else if (req.refine && best != nullptr) {
    const CompareRow start = *best;  // rows grows below
    Step(
        req, Head(kRefineStep, "refine (from " + start.label + ")", {}, start.name),
        [&](CompareRow row) {
          return RunRefine(req, std::move(row), start, configs->base, *truth);
        },
        &result);
  }
  return result;
}

}  // namespace rvlio::experiments
