// rvlio.run, rvlio.refine, rvlio.simulate: the whole-recording calls of the
// public API (rvlio/api.h), with the GIL released and Ctrl-C as
// KeyboardInterrupt.
#include "run_py.h"

#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "config_py.h"
#include "odometry_py.h"
#include "rvlio/api.h"
#include "rvlio/outputs/scan_columns.h"

namespace rvlio::python {
namespace {

constexpr const char* kStopReason = "KeyboardInterrupt";
// rvlio.run calls its `progress` function after each new scan result, and
// while reading without new results at most this often.
constexpr std::chrono::milliseconds kProgressPeriod{200};

// The per-scan table: the columns of scans.csv (outputs/scan_columns.h) as
// numpy arrays, one row per scan: text columns as strings, flags as bool,
// counts as int, the rest float (NaN: none).
py::dict ScanTable(const std::vector<ScanResult>& scans, const std::vector<double>& rss_mb) {
  py::dict table;
  if (scans.empty()) return table;
  const auto n = static_cast<py::ssize_t>(scans.size());
  const auto record = [&](py::ssize_t i) {
    const auto k = static_cast<size_t>(i);
    return ScanRecord{scans[k], k < rss_mb.size() ? rss_mb[k] : std::nan("")};
  };
  const auto fill = [&](auto array, const ScanColumn& c) {
    auto w = array.template mutable_unchecked<1>();
    using T = typename decltype(array)::value_type;
    for (py::ssize_t i = 0; i < n; ++i) w(i) = static_cast<T>(c.value(record(i)));
    return array;
  };
  for (const ScanColumn* c : ScanColumnsOf(scans)) {
    if (c->type == ScanValueType::kText) {
      py::list text;
      for (py::ssize_t i = 0; i < n; ++i) text.append(c->text(record(i)));
      table[c->name] = py::module_::import("numpy").attr("array")(text);
    } else if (c->type == ScanValueType::kFlag) {
      table[c->name] = fill(py::array_t<bool>(n), *c);
    } else if (c->type == ScanValueType::kInteger) {
      table[c->name] = fill(py::array_t<int>(n), *c);
    } else {
      table[c->name] = fill(py::array_t<double>(n), *c);
    }
  }
  return table;
}

py::dict RoundDict(const RefineRound& r) {
  py::dict d;
  d["round"] = r.round;
  d["cost_before"] = r.cost_before;
  d["cost_after"] = r.cost_after;
  d["iterations"] = r.iterations;
  d["max_translation_change_m"] = r.max_translation_change_m;
  d["max_rotation_change_deg"] = r.max_rotation_change_deg;
  d["constraints"] = r.constraints;
  d["rv_active_scans"] = r.rv_active_scans;
  d["degenerate_scans"] = r.degenerate_scans;  // by degeneracy.method (rv: RV active)
  d["total_s"] = r.total_s;
  return d;
}

// f() with the GIL released (a long library call that takes no Python object).
template <class F>
auto WithoutGil(F&& f) -> decltype(f()) {
  py::gil_scoped_release release;
  return f();
}

// The stop callback of a long call: Ctrl-C (Python's signal handlers, run
// every 50 ms with the GIL taken back) stops it.
StopFn StopOn(SignalCheck* signals) {
  return [signals] { return signals->Stop() ? std::string(kStopReason) : std::string(); };
}

ReadWindow Window(double start, double duration) {
  ReadWindow w;
  w.start_s = start;
  w.duration_s = duration;
  return w;
}

// The output folder; None writes nothing. An empty path is refused: the
// library reads "" as "write nothing", and the results would be lost quietly.
std::string OutDir(const py::handle& out) {
  if (out.is_none()) return "";
  std::string dir = PathText(out);
  if (dir.empty()) ValueError("out is an empty path: give a folder, or None to write nothing");
  return dir;
}

// trajectory_imu.tum's rows, or None when output.imu_trajectory is off.
py::object ImuTrajectoryArray(const Trajectory& imu_trajectory) {
  if (imu_trajectory.empty()) return py::none();
  return TrajectoryArray(imu_trajectory);
}

struct RunOutput {
  py::array_t<double> trajectory;
  py::object imu_trajectory;  // None without output.imu_trajectory
  py::dict scans;
  py::object summary;
  std::vector<ScanResult> results;
  Trajectory poses;  // the trajectory as the library has it (exact stamps), for refine
  std::vector<std::string> warnings;
  bool diverged = false;
  bool written = false;
  std::string out;
};

// initial_pose: None, "x,y,z,roll_deg,pitch_deg,yaw_deg", or six numbers.
std::string InitialPoseText(const py::handle& pose) {
  if (pose.is_none()) return "";
  if (py::isinstance<py::str>(pose)) return pose.cast<std::string>();
  std::string text;
  for (const py::handle& v : pose) {
    char number[64];
    std::snprintf(number, sizeof(number), "%.17g", v.cast<double>());
    text += (text.empty() ? "" : ",") + std::string(number);
  }
  return text;
}

RunOutput Run(const py::handle& bag_obj, const py::handle& config, const py::handle& out,
              double start, double duration, const py::object& progress,
              const py::handle& map, const py::handle& initial_pose,
              const py::handle& initial_pose_tum) {
  const std::string bag = PathText(bag_obj);
  RequireExisting(bag, "recording");
  Config defaults;
  RunArgs args;
  args.bag = bag;
  args.options = ConfigArg(config, &defaults).options;
  args.out_dir = OutDir(out);
  args.window = Window(start, duration);
  if (!map.is_none()) args.map = PathText(map);
  args.initial_pose = InitialPoseText(initial_pose);
  if (!initial_pose_tum.is_none()) args.initial_pose_tum = PathText(initial_pose_tum);
  SignalCheck signals;
  args.stop = StopOn(&signals);
  auto last_progress = std::chrono::steady_clock::now();
  int last_scans = 0;
  if (!progress.is_none())
    args.progress = [&](const RunProgress& p) {
      const auto now = std::chrono::steady_clock::now();
      if (p.scans == last_scans && now - last_progress < kProgressPeriod) return;
      last_progress = now;
      last_scans = p.scans;
      signals.CallPython([&] { progress(p.scans, p.fraction); });
    };
  StatusOr<RunResult> result = WithoutGil([&] { return RunRecording(args); });
  signals.Rethrow();  // KeyboardInterrupt (the outputs of the scans done are written)
  RunResult r = Take(std::move(result));
  if (!r.read_error.ok()) Raise(r.read_error);
  RunOutput o;
  o.trajectory = TrajectoryArray(r.trajectory);
  o.imu_trajectory = ImuTrajectoryArray(r.imu_trajectory);
  o.scans = ScanTable(r.scans, r.rss_mb);
  o.summary = ToPython(nlohmann::json::parse(r.summary_json));
  o.results = std::move(r.scans);
  o.poses = std::move(r.trajectory);
  o.warnings = std::move(r.warnings);
  o.diverged = r.divergence.detected;
  o.written = r.written;
  o.out = args.out_dir;
  return o;
}

struct RefineOutput {
  py::array_t<double> trajectory;
  py::object imu_trajectory;
  py::object summary;
  py::list rounds;
  bool converged = false;
  std::vector<std::string> warnings;
  bool written = false;
  py::object control;  // control.csv as {column: list} (None without a control file)
};

// control.csv's text as a table {column: list}: name, role and kind as
// strings, every other column as floats (NaN where empty).
py::object ControlTable(const std::string& csv) {
  if (csv.empty()) return py::none();
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::istringstream h(line); std::getline(h, line, ',');) names.push_back(line);
  std::vector<py::list> columns(names.size());
  for (std::string row; std::getline(in, row);) {
    std::istringstream cells(row);
    std::string cell;
    for (size_t c = 0; c < names.size(); ++c) {
      if (!std::getline(cells, cell, ',')) cell.clear();
      if (c < 3) columns[c].append(cell);
      else columns[c].append(cell.empty() ? std::nan("") : std::stod(cell));
    }
  }
  py::dict table;
  for (size_t c = 0; c < names.size(); ++c) table[py::str(names[c])] = columns[c];
  return table;
}

// `chunk`/`of` of a chunk job (both None: the whole refine).
void SetChunk(const py::handle& chunk, const py::handle& of, RefineArgs* args) {
  if (chunk.is_none() != of.is_none())
    throw py::value_error("chunk and of go together: chunk=K, of=N (1 <= K <= N)");
  if (chunk.is_none()) return;
  args->chunk = chunk.cast<int>();
  args->chunk_count = of.cast<int>();
  if (args->chunk_count < 1 || args->chunk < 1 || args->chunk > args->chunk_count)
    throw py::value_error("chunk=" + std::to_string(args->chunk) + ", of=" +
                          std::to_string(args->chunk_count) + ": needs 1 <= chunk <= of");
}

RefineOutput Refine(const py::handle& bag_obj, const py::handle& init, const py::handle& config,
                    const py::handle& out, double start, double duration, const py::handle& chunk,
                    const py::handle& of, const py::handle& map, const py::handle& control) {
  const std::string bag = PathText(bag_obj);
  RequireExisting(bag, "recording");
  Config defaults;
  RefineArgs args;
  args.bag = bag;
  args.options = ConfigArg(config, &defaults).options;
  args.out_dir = OutDir(out);
  args.window = Window(start, duration);
  SetChunk(chunk, of, &args);
  if (!map.is_none()) args.map = PathText(map);
  if (!control.is_none()) {
    args.control = PathText(control);
    RequireExisting(args.control, "control file");
  }
  if (py::isinstance<RunOutput>(init)) {
    args.init = init.cast<const RunOutput&>().poses;
  } else if (py::isinstance<py::str>(init) || py::hasattr(init, "__fspath__")) {
    args.init_path = PathText(init);
    RequireExisting(args.init_path, "initial trajectory");
  } else {
    throw py::type_error("init must be a TUM file path or the result of rvlio.run");
  }
  SignalCheck signals;
  args.stop = StopOn(&signals);
  StatusOr<RefineRunResult> result = WithoutGil([&] { return RefineRecording(args); });
  signals.Rethrow();
  RefineRunResult r = Take(std::move(result));
  RefineOutput o;
  o.trajectory = TrajectoryArray(r.refine.trajectory);
  o.imu_trajectory = ImuTrajectoryArray(r.imu_trajectory);
  o.summary = ToPython(nlohmann::json::parse(r.summary_json));
  for (const RefineRound& round : r.refine.rounds) o.rounds.append(RoundDict(round));
  o.converged = r.refine.converged;
  o.warnings = r.refine.warnings;
  o.written = r.written;
  o.control = ControlTable(r.control_csv);
  return o;
}

struct MergeOutput {
  py::array_t<double> trajectory;
  py::object imu_trajectory;
  py::array_t<double> map_points;
  py::object summary;
  std::vector<std::string> warnings;
  bool written = false;
};

MergeOutput Merge(const py::iterable& chunks, const py::handle& out, const py::handle& map) {
  MergeArgs args;
  for (const py::handle& c : chunks) args.chunk_dirs.push_back(PathText(c));
  args.out_dir = OutDir(out);
  if (!map.is_none()) args.map = PathText(map);
  StatusOr<MergeResult> result = WithoutGil([&] { return MergeRefineChunks(args); });
  MergeResult r = Take(std::move(result));
  MergeOutput o;
  o.trajectory = TrajectoryArray(r.trajectory);
  o.imu_trajectory = ImuTrajectoryArray(r.imu_trajectory);
  o.map_points = PointsArray(r.map.p);
  o.summary = ToPython(nlohmann::json::parse(r.summary_json));
  o.warnings = r.warnings;
  o.written = r.written;
  return o;
}

py::dict Simulate(const std::string& preset, const py::handle& seed, const py::handle& duration,
                  const py::handle& out, const std::string& name, const std::string& format,
                  const std::string& lidar_msg, const py::handle& set,
                  const py::handle& flight_seed, bool reference_map) {
  SimulateArgs args;
  args.preset = preset;
  if (!seed.is_none()) args.seed = seed.cast<int64_t>();
  if (!flight_seed.is_none()) args.flight_seed = flight_seed.cast<int64_t>();
  args.reference_map = reference_map;
  if (!duration.is_none()) args.duration_s = duration.cast<double>();
  args.overrides = Overrides(set);
  args.lidar_msg = lidar_msg;
  args.out_dir = PathText(out);
  args.name = name;
  args.format = format;
  SignalCheck signals;
  args.stop = StopOn(&signals);
  StatusOr<SimulateResult> result = WithoutGil([&] { return SimulateRecording(args); });
  signals.Rethrow();  // nothing written
  const SimulateResult r = Take(std::move(result));
  py::dict d;
  d["bag"] = r.bag_path;
  d["ground_truth"] = r.gt_path;
  d["config"] = r.config_path;
  d["scans"] = r.scans;
  d["imu_samples"] = r.imu_samples;
  d["duration_s"] = r.duration_s;
  d["reference_map"] = r.reference_map_path.empty() ? py::object(py::none())
                                                     : py::object(py::str(r.reference_map_path));
  d["localizability"] = r.localizability_path.empty() ? py::object(py::none())
                                                      : py::object(py::str(r.localizability_path));
  d["degenerate_scans"] = r.degenerate_scans;
  return d;
}

}  // namespace

void BindRun(py::module_& m) {
  py::class_<RunOutput>(m, "RunResult", "What rvlio.run returns.")
      .def_readonly("trajectory", &RunOutput::trajectory,
                    "(N, 8) [t_s, x, y, z, qx, qy, qz, qw]: trajectory.tum")
      .def_readonly("imu_trajectory", &RunOutput::imu_trajectory,
                    "with output.imu_trajectory: (M, 8) the poses at IMU rate "
                    "(trajectory_imu.tum); None otherwise")
      .def_readonly("scans", &RunOutput::scans,
                    "per-scan table: column name -> (N,) array (the columns of scans.csv, plus "
                    "the velocity vx vy vz)")
      .def_readonly("summary", &RunOutput::summary, "summary.json as a dict")
      .def_readonly("results", &RunOutput::results, "one rvlio.ScanResult per scan")
      .def_readonly("warnings", &RunOutput::warnings)
      .def_readonly("diverged", &RunOutput::diverged, "the divergence monitor fired")
      .def_readonly("written", &RunOutput::written, "the outputs are in `out`")
      .def("__len__", [](const RunOutput& o) { return o.results.size(); })
      .def("__repr__", [](const RunOutput& o) {
        return "<rvlio.RunResult " + std::to_string(o.results.size()) + " scans" +
               (o.written ? " -> " + o.out : std::string()) + ">";
      });
  py::class_<RefineOutput>(m, "RefineResult", "What rvlio.refine returns.")
      .def_readonly("trajectory", &RefineOutput::trajectory,
                    "(N, 8) [t_s, x, y, z, qx, qy, qz, qw]: the refined trajectory.tum")
      .def_readonly("imu_trajectory", &RefineOutput::imu_trajectory,
                    "with output.imu_trajectory: (M, 8) the refined poses at IMU rate; None otherwise")
      .def_readonly("summary", &RefineOutput::summary, "summary.json as a dict")
      .def_readonly("rounds", &RefineOutput::rounds, "one dict per round")
      .def_readonly("converged", &RefineOutput::converged)
      .def_readonly("warnings", &RefineOutput::warnings)
      .def_readonly("written", &RefineOutput::written)
      .def_readonly("control", &RefineOutput::control,
                    "with control=: the quality report (control.csv) as {column: list}, "
                    "e.g. pandas.DataFrame(result.control); None otherwise");

  py::class_<MergeOutput>(m, "MergeResult", "What rvlio.merge returns.")
      .def_readonly("trajectory", &MergeOutput::trajectory,
                    "(N, 8) [t_s, x, y, z, qx, qy, qz, qw]: the merged trajectory.tum")
      .def_readonly("imu_trajectory", &MergeOutput::imu_trajectory,
                    "the chunks' IMU-rate poses merged (when each wrote them); None otherwise")
      .def_readonly("map_points", &MergeOutput::map_points,
                    "(K, 3) the chunks' maps in the merged frame (map.pcd)")
      .def_readonly("summary", &MergeOutput::summary, "summary.json as a dict")
      .def_readonly("warnings", &MergeOutput::warnings)
      .def_readonly("written", &MergeOutput::written);

  m.def("run", &Run, py::arg("bag"), py::arg("config") = py::none(), py::arg("out") = py::none(),
        py::kw_only(), py::arg("start") = 0.0, py::arg("duration") = 0.0,
        py::arg("progress") = py::none(), py::arg("map") = py::none(),
        py::arg("initial_pose") = py::none(), py::arg("initial_pose_tum") = py::none(),
        "`rvlio run`: the odometry over a recording. With `out`, writes trajectory.tum, map.pcd, "
        "scans.csv and summary.json there, as the command does. map (a PCD/PLY path) with "
        "initial_pose (x, y, z, roll_deg, pitch_deg, yaw_deg: six numbers or that text) or "
        "initial_pose_tum (a TUM path): localize in that reference map, as `rvlio run --map` "
        "(the table gains map_overlap and localized). progress(scans, fraction) is "
        "called after each new scan result (and every 0.2 s while reading without one); an "
        "exception it raises stops the run and is raised. Ctrl-C "
        "raises KeyboardInterrupt (with `out`, the outputs of the scans done are written first).");
  m.def("refine", &Refine, py::arg("bag"), py::arg("init"), py::arg("config") = py::none(),
        py::arg("out") = py::none(), py::kw_only(), py::arg("start") = 0.0,
        py::arg("duration") = 0.0, py::arg("chunk") = py::none(), py::arg("of") = py::none(),
        py::arg("map") = py::none(), py::arg("control") = py::none(),
        "`rvlio refine`: offline batch refinement from `init` (a TUM path or an rvlio.run "
        "result). With `out`, writes trajectory.tum, map.pcd and summary.json there. "
        "map: a reference map (PCD/PLY) every scan is also held to (`refine --map`). "
        "control: a control file (`refine --control`): outputs in the survey frame, "
        "result.control the quality report. "
        "chunk=K, of=N: the chunk job `rvlio refine --chunk K --of N` (also writes chunk.json; "
        "join the N output folders with rvlio.merge).");
  m.def("merge", &Merge, py::arg("chunks"), py::arg("out") = py::none(), py::kw_only(),
        py::arg("map") = py::none(),
        "`rvlio merge`: joins the output folders of the N chunk jobs (any order) into one "
        "trajectory and map; with `out`, writes trajectory.tum, map.pcd and summary.json there. "
        "map: the reference the chunks were refined with (`merge --map`): the summary gains "
        "localization.deviation, and with `out` map.pcd gains deviation_m and deviation.csv "
        "is written. A missing or mismatched chunk or map raises ValueError naming it.");
  m.def("simulate", &Simulate, py::arg("preset") = "tunnel", py::kw_only(),
        py::arg("seed") = py::none(), py::arg("duration") = py::none(), py::arg("out"),
        py::arg("name") = "", py::arg("format") = "bag", py::arg("lidar_msg") = "pointcloud2",
        py::arg("set") = py::none(), py::arg("flight_seed") = py::none(),
        py::arg("reference_map") = false,
        "`rvlio simulate`: writes OUT/NAME.bag (or .mcap / .db3), OUT/NAME_gt.tum and "
        "OUT/NAME.yaml (the config for rvlio.Config.load); returns their paths and counts. "
        "flight_seed: another flight through the same world (--flight-seed); reference_map: "
        "also OUT/reference_map.pcd, a survey of the world (--reference-map). "
        "localizability: OUT/localizability.csv, the true per-scan localizability (None with "
        "localizability.enabled false), degenerate_scans: its degenerate scans "
        "(docs/degeneracy_truth.md). Ctrl-C raises KeyboardInterrupt and leaves no recording.");
}

}  // namespace rvlio::python
