#pragma once
// The public C++ API of rvlio (target rvlio::io): the whole-recording calls
// that the `rvlio` command runs -- `run`, `refine`, `simulate`, `eval` -- as
// library functions. The command-line tool is a thin layer over them: given
// the same inputs and an output folder, a call writes the same files, byte for
// byte (except for timings and memory figures), as the command.
//
// For scan-by-scan use without a recording, see rvlio/odometry/odometry.h
// (rvlio::Odometry, target rvlio::core): AddImu / AddScan / Poll / Finish.
//
// Conventions (as everywhere in rvlio): errors are Status::InvalidInput (bad
// input or configuration; the message names the file/topic/key),
// Status::IoError (an output that cannot be written) or Status::Internal;
// nothing is printed and the process is never exited. A
// call that is stopped (`stop`) returns normally with `stopped` set.
//
// Configuration: LoadConfig (rvlio/config/config.h) gives the Configuration from
// YAML files plus `key=value` overrides; DumpYaml writes it back.
//
// No JSON type is part of this API: results carry typed figures, and the
// text of summary.json (or chunk.json) as written, for programs that want
// the file without reading it back.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/eval/degeneracy_scores.h"
#include "rvlio/eval/evaluate.h"
#include "rvlio/eval/map_metrics.h"
#include "rvlio/config/config.h"
#include "rvlio/formats/control_file.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/formats/sensor_stream.h"
#include "rvlio/odometry/divergence.h"
#include "rvlio/odometry/odometry.h"
#include "rvlio/config/configuration.h"
#include "rvlio/outputs/run_outputs.h"
#include "rvlio/refine/refine.h"
#include "rvlio/refine/jobs.h"
#include "rvlio/version.h"

namespace rvlio {

// Polled between messages (run, simulate) and between rounds (refine). An
// empty string goes on; a non-empty one stops the call as SIGINT stops the
// command and is recorded as the cause (summary.json "signal"), e.g.
// "SIGINT" or "KeyboardInterrupt". Called on the calling thread.
using StopFn = std::function<std::string()>;

// ---------------------------------------------------------------------------
// run: the odometry over a recording
// ---------------------------------------------------------------------------

struct RunProgress {
  int scans = 0;         // results so far
  double fraction = 0.0; // share of the recording's time span read (may pass 1 slightly)
  double wall_s = 0.0;   // since the call started reading
  const DivergenceReport* divergence = nullptr;  // the monitor's findings so far
};

struct RunArgs {
  std::string bag;          // ROS1 .bag, ROS 2 .db3, .mcap or bag folder
  Configuration options;  // e.g. LoadConfig(files, overrides)
  // When not empty: created if needed; receives trajectory.tum, map.pcd,
  // scans.csv and summary.json (all or none, atomically) and, while the run
  // goes, trajectory.partial.tum. Empty: nothing is written.
  std::string out_dir;
  ReadWindow window;  // part of the recording (default: all of it)
  // Localization in a reference map (docs/survey.md): when map is not empty,
  // the run is in that map's frame, starting from initial_pose
  // ("x,y,z,roll_deg,pitch_deg,yaw_deg") or initial_pose_tum (a TUM file);
  // scans.csv gains map_overlap and localized, summary.json "localization".
  std::string map;
  std::string initial_pose;
  std::string initial_pose_tum;
  StopFn stop;
  // Called after every message read and once after the end of the input.
  std::function<void(const RunProgress&)> progress;
  // A source to read instead of the recording `bag` (not owned), e.g. the
  // network messages of `rvlio live` (formats/live_source.h): read as it
  // is (`window` must be the default; no extrinsic from the recording);
  // `bag` then only names it in summary.json.
  SensorBagReader* source = nullptr;
  // Called on the calling thread with each scan result as it is estimated
  // (in order, once each), in the user's frame (as trajectory.tum), with the
  // odometry that made it and the odometry's local frame (where its
  // MapPoints are) relative to the user's frame (math/local_origin.h).
  std::function<void(const ScanResult&, const Odometry&, const LocalOrigin&)> on_result;
  // Called once after the last scan with the output map (map.pcd's points
  // and attributes, in the user's frame, double precision;
  // MapPointsAsStored, outputs/run_outputs.h, rounds them as the file
  // does), whether or not out_dir is set; not called when no scan was done.
  std::function<void(const MapCloud&)> on_map;
};

struct RunResult {
  std::vector<ScanResult> scans;  // one per processed scan (the rows of scans.csv)
  std::vector<double> rss_mb;     // process resident memory when each scan was done, MB
  Trajectory trajectory;          // T_world_imu at each scan end (trajectory.tum)
  // With output.imu_trajectory: T_world_imu at every IMU sample from the
  // first scan end to the last and at every scan end (trajectory_imu.tum,
  // imu/imu_rate_trajectory.h); empty otherwise.
  Trajectory imu_trajectory;
  // The figures summary.json writes under the same names, typed: read these,
  // not the JSON.
  double sequence_duration_s = 0.0;  // first to last message read
  TimingStats per_scan;              // estimator time per scan (per_scan_ms, estimator_total_s)
  double wall_s = 0.0;               // reading and estimating
  double real_time_factor = 0.0;     // sequence duration / estimator time (0: none measured)
  double real_time_factor_wall = 0.0;  // sequence duration / wall_s
  // summary.json's text (as written to out_dir, or as it would be): the
  // figures above with the run's configuration, statistics and checks.
  std::string summary_json;
  std::vector<std::string> warnings;  // reader, estimator and output warnings
  DivergenceReport divergence;
  std::string lidar_layout;       // the reader's name for the point layout
  bool stopped = false;           // `stop` ended the run early (outputs hold the scans done)
  std::string stop_reason;        // what `stop` returned
  // A read error after some scans: the outputs hold the scans read before it.
  Status read_error;
  bool written = false;           // the outputs are in out_dir
};

// Errors: an unreadable recording or configuration, an output folder that
// cannot be written, no scan processed (the message says why: topic, ranges,
// IMU) -- nothing is written then. A stop before the first scan returns a
// result with stopped set and no scans (nothing written).
StatusOr<RunResult> RunRecording(const RunArgs& args);

// ---------------------------------------------------------------------------
// refine: offline batch refinement from an initial trajectory
// ---------------------------------------------------------------------------

struct RefineArgs {
  std::string bag;
  std::string init_path;  // TUM file, read when `init` is empty; summary.json "init"
  Trajectory init;        // the initial trajectory (e.g. RunResult::trajectory)
  Configuration options;
  std::string out_dir;    // empty: nothing written; else trajectory.tum, map.pcd, summary.json
  ReadWindow window;
  // When not empty, the state after each round goes to checkpoint_dir/refine.checkpoint;
  // with resume, the refinement continues from it (same inputs required).
  std::string checkpoint_dir;
  bool resume = false;
  StopFn stop;  // polled while reading and between rounds: the last completed round is the result
  std::function<void(const RefineRound&)> on_round;  // after each round
  std::function<void(int rounds_done)> on_resume;    // a checkpoint was loaded
  // Chunk job (`rvlio refine --chunk K --of N`, refine/jobs.h): when
  // chunk_count > 0, refines only chunk `chunk` (1-based) of chunk_count
  // chunks of the initial trajectory's span, overlapping by
  // refine.job_overlap_s; only that chunk's scans (and the IMU
  // samples around them) are kept while reading. out_dir then also receives
  // chunk.json, which MergeRefineChunks reads.
  int chunk = 0;
  int chunk_count = 0;
  // A reference map (PCD or PLY, metres) in the initial trajectory's frame:
  // every scan is also held to it (`refine --map`, docs/survey.md).
  std::string map;
  // A control file (`refine --control`, docs/control.md): the initial
  // trajectory is brought into the survey frame and refined with the control
  // points as factors; outputs in the survey frame, out_dir also receives
  // control.csv. GNSS fixes (options.gnss.topic) are ties as well.
  std::string control;
};

struct RefineRunResult {
  RefineResult refine;          // trajectory, map points, rounds, stats, warnings
  // With output.imu_trajectory: the refined trajectory at IMU rate
  // (trajectory_imu.tum, as RunResult::imu_trajectory); empty otherwise.
  Trajectory imu_trajectory;
  DivergenceReport divergence;  // the checks of the refined result
  std::string summary_json;     // summary.json's text (as RunResult::summary_json)
  bool stopped = false;         // `stop` ended it (after a round, or while reading)
  std::string stop_reason;
  bool read_complete = true;    // false: stopped while reading; nothing refined or written
  bool written = false;
  std::optional<RefineJobSpan> job;  // a chunk job's span (chunk.json; none otherwise)
  std::string chunk_json;       // chunk.json's text of a chunk job (empty otherwise)
  // With a control file: control.csv's text (the residual of every row) and
  // its rows (SummarizeControlRole, formats/control_file.h, gives summary.json
  // "control"); empty otherwise.
  std::string control_csv;
  std::vector<ControlResidual> control;
  int gnss_fixes = 0;     // GNSS fixes used as ties (gnss.topic)
  int gnss_outliers = 0;  // fixes the robust alignment left out
};

// Errors: unreadable inputs, a checkpoint that is missing or belongs to other
// inputs, a failed refinement (the message names the bag and init).
StatusOr<RefineRunResult> RefineRecording(const RefineArgs& args);

// ---------------------------------------------------------------------------
// merge: the chunk jobs of one recording into one trajectory and map
// ---------------------------------------------------------------------------

struct MergeArgs {
  std::vector<std::string> chunk_dirs;  // the output folders of `refine --chunk K --of N`, any order
  std::string out_dir;  // empty: nothing written; else trajectory.tum, map.pcd, summary.json
  // The reference map the chunks were refined with (`refine --map`): the
  // merged map.pcd gains deviation_m and deviation.csv is written, as after
  // `refine --map` (docs/survey.md). Empty: no deviation.
  std::string map;
};

// How one chunk was carried into the merged frame (summary.json "chunks", same names).
struct MergedChunk {
  int chunk = 1;  // 1-based
  std::string dir;
  size_t scans = 0;
  int shared_poses = 0;         // with the previous chunk (0 for chunk 1)
  double translation_m = 0.0;   // of the chunk's transform into the merged frame
  double rotation_deg = 0.0;
  double residual_rms_m = 0.0;  // over the shared poses after alignment
  double residual_max_m = 0.0;
  double residual_max_deg = 0.0;
};

struct MergeResult {
  Trajectory trajectory;                    // T_world_imu, the merged frame is chunk 1's
  // The chunks' trajectory_imu.tum merged as `trajectory` (when every chunk
  // wrote one: output.imu_trajectory); empty otherwise.
  Trajectory imu_trajectory;
  // The chunks' maps carried into that frame, re-voxelized, with the
  // attributes they have (scan_index: rows of `trajectory`).
  MapCloud map;
  std::vector<MergedChunk> chunks;          // in order 1..N
  std::string summary_json;                 // summary.json's text
  std::vector<std::string> warnings;        // the chunks' warnings, each once
  // Chunks refined with --control: the merged control.csv (each row from the
  // chunk that owns its tie time, in the merged frame); empty otherwise.
  std::string control_csv;
  std::vector<ControlResidual> control;
  bool written = false;
};

// InvalidInput (one line naming the folder or the chunk) for a folder without
// a readable chunk.json, trajectory.tum or map.pcd, chunks of different N,
// options, initial trajectory or overlap, a chunk given twice, a missing
// chunk K, or neighbours that share too few poses (refine/jobs.h);
// and for a `map` that is not the one the chunks were refined with (by
// content) or chunks refined without one.
StatusOr<MergeResult> MergeRefineChunks(const MergeArgs& args);

// ---------------------------------------------------------------------------
// simulate: a simulated recording with its ground truth and sensor config
// ---------------------------------------------------------------------------

struct SimulateArgs {
  std::string preset = "tunnel";         // sim::PresetNames()
  std::optional<int64_t> seed;           // default: the preset's (the world's seed)
  std::optional<int64_t> flight_seed;    // default: seed (simulator key flight_seed)
  bool reference_map = false;            // also write OUT_DIR/reference_map.pcd (survey.enabled)
  bool reference_map_only = false;       // write only OUT_DIR/reference_map.pcd
  std::optional<double> duration_s;      // default: the preset's
  std::vector<std::string> overrides;    // simulator "key=value", applied last
  std::string lidar_msg = "pointcloud2"; // or "livox"
  std::string out_dir;                   // created if missing (required)
  std::string name;                      // file stem (default: the preset)
  std::string format = "bag";            // bag (ROS1) | mcap | db3 | ouster-pcap | ouster-bag
  std::string mcap_compression = "zstd"; // zstd | lz4 | none | unchunked (mcap only)
  StopFn stop;                           // a stop leaves no recording
  // Called with the path the recording is written to before it is moved
  // into out_dir (a staging folder inside it), e.g. to remove its temporary
  // file when the process is aborted.
  std::function<void(const std::string& staged_recording)> staged;
};

// What `rvlio simulate` simulated, in OUT_DIR/simulation.json: preset, name,
// seed, flight_seed, duration_s, start_time_s, recording (file name),
// recording_hash (FileContentHash, 16 hex digits), scans,
// localizability_scans and localizability_stamps_s {first, last}.
inline constexpr const char* kSimulationFile = "simulation.json";

struct SimulateResult {
  std::string bag_path, gt_path, config_path;  // NAME.bag|mcap|db3, NAME_gt.tum, NAME.yaml
  // reference_map.pcd (binary PCD, x y z float32, world frame = the ground
  // truth's, m) when the survey ran, else "".
  std::string reference_map_path;
  int64_t reference_map_points = 0;
  int reference_map_stations = 0;
  // localizability.csv (the true per-scan localizability, sim/localizability.h)
  // when localizability.enabled, else ""; its scans flagged degenerate.
  std::string localizability_path;
  // NAME_control.csv (marks.enabled: the stop-and-go marks in the survey
  // frame) and NAME_gt_survey.tum (marks or gnss: the ground truth in the
  // survey frame), else "".
  std::string control_path, gt_survey_path;
  int64_t degenerate_scans = 0;
  double reference_map_s = 0.0;  // wall time of the survey
  int64_t scans = 0, imu_samples = 0;
  int rows = 0, cols = 0;     // LiDAR rows x columns
  double duration_s = 0.0;    // of simulated data
  double wall_s = 0.0, cpu_s = 0.0;
  bool stopped = false;       // nothing was written
  std::string stop_reason;
};

StatusOr<SimulateResult> SimulateRecording(const SimulateArgs& args);
// Where SimulateRecording writes the recording: OUT_DIR/NAME.FORMAT.
std::string SimulatedRecordingPath(const SimulateArgs& args);

// ---------------------------------------------------------------------------
// eval: APE / RPE with the definitions of evo
// ---------------------------------------------------------------------------

// Reads both trajectories (TUM, or KITTI at 10 Hz, by column count) and
// evaluates (rvlio/eval/evaluate.h; Evaluate() takes trajectories directly).
StatusOr<EvalResult> EvaluateFiles(const std::string& gt_path, const std::string& est_path,
                                   const EvalOptions& options);

// eval --degeneracy: a run's per-scan degeneracy detection against the
// simulator's true localizability (eval/degeneracy.h, docs/degeneracy_truth.md).
struct DegeneracyEvalResult {
  // Where the detection came from: "degenerate,weak_dir" (the degeneracy
  // columns of scans.csv) or "rv_active,n_alpha" (a run without them).
  std::string detection_columns;
  std::string scans_path, truth_path, gt_path, est_path;
  size_t truth_scans = 0, run_scans = 0;
  DegeneracyScores scores;
};
struct DegeneracyEvalArgs {
  std::string run_dir;    // scans.csv, trajectory.tum
  std::string truth_dir;  // localizability.csv, NAME_gt.tum (`rvlio simulate` output)
  std::string gt_path;    // the ground truth; "" = the one *_gt.tum in truth_dir
  // > 0: a truth scan is degenerate when its `ratio` column is below this
  // (instead of its `degenerate` column, the simulation's
  // localizability.degenerate_ratio).
  double degenerate_ratio = 0.0;
  EvalOptions eval;  // alignment and time association (max_dt)
};
// Reads RUN_DIR/scans.csv (columns by header name), RUN_DIR/trajectory.tum,
// TRUTH_DIR/localizability.csv and the ground truth. InvalidInput naming the
// file for a missing file or column, a non-finite value, or no scans matched
// by time.
StatusOr<DegeneracyEvalResult> EvaluateDegeneracyFiles(const DegeneracyEvalArgs& args);

// ---------------------------------------------------------------------------
// eval --map: a map against a reference cloud (eval/map_metrics.h)
// ---------------------------------------------------------------------------

// Reads both clouds (PCD or PLY, formats/point_cloud_file.h) and evaluates the
// map against the reference. InvalidInput, one line naming the file(s), for
// an unreadable, empty, truncated or NaN cloud, or clouds that do not
// overlap, or a profile step giving more than kMaxProfileBins bins. Reads
// only. `progress` (optional): the share of the searches done.
StatusOr<MapEvalResult> EvaluateMapFiles(const std::string& map_path, const std::string& ref_path,
                                         const MapEvalOptions& options,
                                         const MapEvalProgress& progress = nullptr);

}  // namespace rvlio
