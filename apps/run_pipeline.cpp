#include "run_pipeline.h"
#include "json_text.h"

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "interrupt.h"
#include "divergence_cli.h"
#include "extrinsic_json.h"
#include "rvlio/io/atomic_file.h"
#include "rvlio/io/config.h"
#include "rvlio/io/run_outputs.h"
#include "rvlio/io/sensor_bag.h"
#include "rvlio/io/trajectory_io.h"
#include "rvlio/io/tum_stream.h"
#include "rvlio/odometry/odometry.h"

namespace rvlio::cli {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kPartialTrajectory = "trajectory.partial.tum";

double SecondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A progress line on stderr for long runs, only when stderr is a terminal.
class Progress {
 public:
  Progress(bool enabled, double bag_start_s, double bag_end_s)
      : enabled_(enabled && isatty(STDERR_FILENO)), start_s_(bag_start_s), end_s_(bag_end_s) {}
  void Update(int scans, TimeNs bag_time_ns) {
    if (!enabled_) return;
    const double wall = SecondsSince(t0_);
    if (wall < 3.0 || wall - last_print_ < 0.5) return;
    last_print_ = wall;
    const double done = (NsToSeconds(bag_time_ns) - start_s_) / std::max(1e-9, end_s_ - start_s_);
    const double eta = done > 0.01 ? wall * (1.0 - done) / done : 0.0;
    std::fprintf(stderr, "\r  scans %d  %.1f scans/s  %3.0f%%  ETA %.0f s   ", scans,
                 scans / wall, 100.0 * std::min(1.0, done), eta);
    printed_ = true;
  }
  ~Progress() {
    if (printed_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  double start_s_, end_s_;
  Clock::time_point t0_ = Clock::now();
  double last_print_ = 0.0;
  bool printed_ = false;
};

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

struct RunData {
  std::vector<ScanResult> results;
  std::vector<double> rss_mb;  // resident memory when each result came out
  TimeNs first_ns = -1, last_ns = -1;
  double wall_s = 0.0;
  std::string interrupted_by;  // "SIGINT"/"SIGTERM" when a signal stopped the run
};

Status WriteOutputs(const RunRequest& req, const OdometryOptions& options, const Odometry& odo,
                    const SensorReaderStats& reader_stats, const RunData& data,
                    const std::string& layout, const std::vector<std::string>& warnings,
                    RunOutcome* outcome) {
  OutputStage stage(req.out_dir);
  if (Status s = stage.Open(); !s.ok()) return s;
  if (Status s = WriteTum(stage.Path("trajectory.tum"), ToTrajectory(data.results)); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteMapPcd(stage.Path("map.pcd"), odo.MapPoints()); !s.ok())
    return stage.Explain(s);
  if (Status s = WriteScansCsv(stage.Path("scans.csv"), data.results, data.rss_mb); !s.ok())
    return stage.Explain(s);
  const TimingStats t = ComputeTimingStats(data.results);
  const double duration_s =
      data.first_ns >= 0 ? NsToSeconds(data.last_ns - data.first_ns) : 0.0;
  nlohmann::json j;
  j["version"] = RVLIO_VERSION;
  j["command"] = "run";
  j["bag"] = req.bag;
  j["lidar_layout"] = layout;
  j["backend"] = EnumName(options.backend);
  j["config"] = ToJson(options);
  j["scan_count"] = data.results.size();
  j["sequence_duration_s"] = duration_s;
  j["per_scan_ms"] = {{"median", t.median_ms}, {"p95", t.p95_ms}, {"max", t.max_ms}};
  j["estimator_total_s"] = t.total_ms / 1000.0;
  j["wall_s"] = data.wall_s;
  j["real_time_factor"] = t.total_ms > 0 ? duration_s / (t.total_ms / 1000.0) : 0.0;
  j["real_time_factor_wall"] = data.wall_s > 0 ? duration_s / data.wall_s : 0.0;
  j["peak_memory_mb"] = PeakMemoryMb();
  j["rv_active_scans"] = RvActiveScans(data.results);
  j["stats"] = StatsJson(odo.stats(), reader_stats);
  j["divergence"] = DivergenceJson(odo.divergence());
  if (odo.stats().extrinsic.enabled) j["extrinsic"] = ExtrinsicJson(odo.stats().extrinsic);
  j["warnings"] = warnings;
  j["interrupted"] = !data.interrupted_by.empty();
  if (!data.interrupted_by.empty()) {
    j["signal"] = data.interrupted_by;
    j["last_stamp_s"] = data.results.empty() ? 0.0 : NsToSeconds(data.results.back().t_ns);
  }
  outcome->scans = static_cast<int>(data.results.size());
  outcome->diverged = odo.divergence().detected;
  outcome->median_ms = t.median_ms;
  outcome->real_time_factor = j["real_time_factor"];
  if (Status s = WriteFileAtomically(stage.Path("summary.json"), JsonText(j) + "\n"); !s.ok())
    return stage.Explain(s);
  return stage.Commit();
}

// Why a run produced no scan at all, naming the topic and the keys to look at
// (nothing is written then, so the counts are in the message).
std::string NoScanMessage(const RunRequest& req, const OdometryOptions& o,
                          const SensorReaderStats& r, const OdometryStats& odo) {
  const std::string topic = "lidar.topic '" + o.lidar.topic + "' in " + req.bag;
  if (r.scans == 0 && r.empty_scans > 0) {
    char range[96];
    std::snprintf(range, sizeof(range), "lidar.min_range %g m, lidar.max_range %g m",
                  o.lidar.min_range, o.lidar.max_range);
    return "every one of the " + std::to_string(r.empty_scans) + " scans on " + topic +
           " is empty after dropping " + std::to_string(r.invalid_points) + " invalid and " +
           std::to_string(r.out_of_range_points) + " out-of-range points (" + range + ")";
  }
  if (r.imu_samples == 0)
    return "no usable IMU sample on imu.topic '" + o.imu.topic + "' in " + req.bag + " (" +
           std::to_string(r.imu_invalid) + " invalid, " + std::to_string(r.imu_duplicates) +
           " repeated, " + std::to_string(r.imu_non_monotonic) + " out of order)";
  return "no scan could be processed from " + req.bag + ": " + std::to_string(r.scans) +
         " scans read, " + std::to_string(r.scans_before_first_imu) +
         " before the first IMU sample, " + std::to_string(odo.scans_too_few_points) +
         " with too few points, " + std::to_string(odo.scans_before_imu) +
         " during the IMU initialization";
}

// Appends the poses of the results not streamed yet to trajectory.partial.tum;
// a write error stops the streaming with one warning (the run goes on).
void StreamNewPoses(const std::vector<ScanResult>& results, size_t* streamed, TumStream* stream,
                    std::vector<std::string>* warnings) {
  for (; *streamed < results.size(); ++*streamed) {
    if (!stream->is_open()) continue;
    StampedPose pose;
    pose.t_ns = results[*streamed].t_ns;
    pose.p_world_imu = results[*streamed].T_world_imu.t;
    pose.q_world_imu = results[*streamed].T_world_imu.quaternion();
    if (Status s = stream->Append(pose); !s.ok())
      warnings->push_back(s.message() + "; the partial trajectory is no longer written");
  }
}

// The one line of an interrupted run; returns its exit status (130 / 143).
int ReportInterrupt(const RunRequest& req, const RunData& data) {
  if (data.results.empty()) {
    std::fprintf(stderr, "rvlio run: interrupted by %s before the first scan was done; nothing "
                 "written\n", data.interrupted_by.c_str());
  } else {
    std::fprintf(stderr, "rvlio run: interrupted by %s after %zu scans (up to t = %.3f s): wrote "
                 "trajectory.tum, map.pcd, scans.csv and summary.json to %s\n",
                 data.interrupted_by.c_str(), data.results.size(),
                 NsToSeconds(data.results.back().t_ns), req.out_dir.c_str());
  }
  return InterruptExitCode();
}

// A number in its shortest form ("0.1", "2e-05").
std::string Short(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

}  // namespace

nlohmann::json ReaderStatsJson(const SensorReaderStats& r) {
  return {{"scans", r.scans},
          {"imu_samples", r.imu_samples},
          {"empty_scans", r.empty_scans},
          {"invalid_points", r.invalid_points},
          {"out_of_range_points", r.out_of_range_points},
          {"imu_invalid", r.imu_invalid},
          {"scans_before_first_imu", r.scans_before_first_imu},
          {"imu_duplicates", r.imu_duplicates},
          {"imu_non_monotonic", r.imu_non_monotonic},
          {"imu_gaps", r.imu_gaps},
          {"imu_max_gap_s", r.imu_max_gap_s}};
}

double PeakMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KB on Linux
}

double CurrentMemoryMb() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0.0;
  long total_pages = 0, resident_pages = 0;
  const int n = std::fscanf(f, "%ld %ld", &total_pages, &resident_pages);
  std::fclose(f);
  if (n != 2) return 0.0;
  return static_cast<double>(resident_pages) * static_cast<double>(::sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

OutputStage::~OutputStage() {
  if (stage_dir_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(stage_dir_, ec);
}

// Staging folders of processes that no longer exist (killed, or aborted by a
// second signal while writing) are removed when the next run stages there.
void RemoveStaleStages(const std::string& out_dir) {
  const std::string prefix = ".rvlio_stage.";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(out_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)) {
      std::error_code ignored;
      std::filesystem::remove_all(e.path(), ignored);
    }
  }
}

Status OutputStage::Open() {
  RemoveStaleStages(out_dir_);
  // Unique per run, not per process: compare runs several variants in one
  // process, and two runs of one process may share an output folder.
  std::string name = (std::filesystem::path(out_dir_) /
                      (".rvlio_stage." + std::to_string(::getpid()) + ".XXXXXX"))
                         .string();
  if (::mkdtemp(name.data()) == nullptr) {
    const std::string why = std::strerror(errno);
    return Status::InvalidInput("cannot write to output folder " + out_dir_ + ": " + why);
  }
  stage_dir_ = name;
  return Status::Ok();
}

std::string OutputStage::Path(const std::string& name) {
  names_.push_back(name);
  return (std::filesystem::path(stage_dir_) / name).string();
}

Status OutputStage::Commit() {
  for (const std::string& name : names_) {
    const std::string from = (std::filesystem::path(stage_dir_) / name).string();
    const std::string to = (std::filesystem::path(out_dir_) / name).string();
    if (std::rename(from.c_str(), to.c_str()) != 0)
      return Status::InvalidInput("cannot move " + name + " into " + out_dir_ + ": " +
                                  std::strerror(errno));
  }
  return Status::Ok();
}

Status OutputStage::Explain(const Status& s) const {
  std::string message = s.message();
  const std::string staged = stage_dir_ + "/";
  const std::string final_dir = (std::filesystem::path(out_dir_) / "").string();
  for (size_t at = message.find(staged); at != std::string::npos; at = message.find(staged, at))
    message.replace(at, staged.size(), final_dir);
  return s.code() == StatusCode::kInternal ? Status::Internal(message)
                                           : Status::InvalidInput(message);
}

std::vector<std::string> ReaderWarnings(const SensorReaderStats& r, const LidarOptions& lidar,
                                        const ImuOptions& imu) {
  std::vector<std::string> w;
  const std::string scans_on = " on lidar.topic '" + lidar.topic + "'";
  const std::string imu_on = " on imu.topic '" + imu.topic + "'";
  auto add = [&w](int64_t n, const std::string& text) {
    if (n > 0) w.push_back(std::to_string(n) + text);
  };
  add(r.empty_scans, " scans" + scans_on + " had no valid point in range and were skipped");
  add(r.scans_before_first_imu,
      " scans" + scans_on + " came before the first IMU sample and were skipped");
  add(r.imu_invalid, " IMU samples" + imu_on + " with NaN/Inf values were dropped");
  add(r.imu_duplicates, " IMU samples" + imu_on + " repeat the previous stamp and were dropped");
  add(r.imu_non_monotonic,
      " IMU samples" + imu_on + " are older than the previous one and were dropped");
  if (r.imu_gaps > 0) {
    char text[160];
    std::snprintf(text, sizeof(text), " (longest %.3f s) were bridged by the estimator",
                  r.imu_max_gap_s);
    w.push_back("IMU gaps longer than imu.max_gap " + Short(imu.max_gap) + " s" + imu_on + ": " +
                std::to_string(r.imu_gaps) + text);
  }
  return w;
}

bool PrepareOutputDir(const std::string& command, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    Fail(command, "cannot create output folder " + dir + ": " + ec.message());
    return false;
  }
  const std::string probe = (std::filesystem::path(dir) / ".rvlio_write_test").string();
  if (Status s = WriteFileAtomically(probe, "ok\n"); !s.ok()) {
    Fail(command, "output folder " + dir + " is not writable: " + s.message());
    return false;
  }
  std::filesystem::remove(probe, ec);
  return true;
}

int RunOdometryOnBag(const RunRequest& req, RunOutcome* outcome) {
  std::vector<std::string> config_warnings;
  StatusOr<OdometryOptions> options =
      LoadConfig(req.config_files, req.overrides, &config_warnings);
  if (!options.ok()) return Fail("run", options.status().message());
  for (const auto& w : config_warnings) std::fprintf(stderr, "rvlio run: warning: %s\n", w.c_str());
  StatusOr<std::unique_ptr<Odometry>> odo = Odometry::Create(*options);
  if (!odo.ok()) return Fail("run", odo.status().message());
  StatusOr<std::unique_ptr<SensorBagReader>> reader =
      OpenSensorStream(req.bag, options->lidar, options->imu, req.window, options->io);
  if (!reader.ok()) return Fail("run", reader.status().message());
  std::error_code ec;
  const bool out_dir_existed = std::filesystem::exists(req.out_dir, ec);
  if (!PrepareOutputDir("run", req.out_dir)) return 2;
  StatusOr<BagInfo> info = ReadBagSpan(req.bag);
  Progress progress(!req.quiet, info.ok() ? info->start_s : 0.0, info.ok() ? info->end_s : 1.0);

  RunData data;
  std::vector<std::string> stream_warnings;
  TumStream partial;  // trajectory.partial.tum: what a killed run leaves (tum_stream.h)
  if (Status s = partial.Open((std::filesystem::path(req.out_dir) / kPartialTrajectory).string());
      !s.ok())
    stream_warnings.push_back(s.message() + "; the partial trajectory is not written");
  size_t streamed = 0;
  const auto t0 = Clock::now();
  ImuSample imu;
  Scan scan;
  Status read_error;
  size_t divergence_warned = 0;
  for (;;) {
    if (Interrupted()) {  // the scans done so far are the outputs; pending ones are dropped
      data.interrupted_by = InterruptSignalName();
      break;
    }
    StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
    if (!m.ok()) {
      read_error = m.status();  // keep what was read: outputs are still written
      break;
    }
    if (*m == SensorMessage::kEnd) break;
    const TimeNs t = *m == SensorMessage::kImu ? imu.t_ns : scan.t_end_ns;
    if (data.first_ns < 0) data.first_ns = t;
    data.last_ns = std::max(data.last_ns, t);
    if (*m == SensorMessage::kImu) (*odo)->AddImu(imu);
    else (*odo)->AddScan(std::move(scan));
    (*odo)->Poll(&data.results);
    StreamNewPoses(data.results, &streamed, &partial, &stream_warnings);
    (void)partial.SyncIfDue();  // a failure surfaces at the next Append
    if (data.rss_mb.size() < data.results.size())
      data.rss_mb.resize(data.results.size(), CurrentMemoryMb());
    progress.Update(static_cast<int>(data.results.size()), t);
    WarnDivergence("run", (*odo)->divergence(), &divergence_warned);
  }
  if (data.interrupted_by.empty()) {
    (*odo)->Finish(&data.results);
    WarnDivergence("run", (*odo)->divergence(), &divergence_warned);
  }
  data.rss_mb.resize(data.results.size(), CurrentMemoryMb());
  data.wall_s = SecondsSince(t0);
  const SensorReaderStats& reader_stats = (*reader)->stats();
  std::vector<std::string> warnings = ReaderWarnings(reader_stats, options->lidar, options->imu);
  for (const auto& w : (*odo)->warnings()) warnings.push_back(w);
  for (const auto& w : (*reader)->warnings()) warnings.push_back(w);
  for (const auto& w : stream_warnings) warnings.push_back(w);
  if (data.results.empty()) {  // nothing to write: nothing new in the output folder
    partial.Remove();
    if (!out_dir_existed) std::filesystem::remove(req.out_dir, ec);  // only if empty
    if (!data.interrupted_by.empty()) return ReportInterrupt(req, data);
    if (!read_error.ok()) return Fail("run", read_error.message());
    return Fail("run", NoScanMessage(req, *options, reader_stats, (*odo)->stats()));
  }
  const Status written = WriteOutputs(req, *options, **odo, reader_stats, data,
                                      (*reader)->lidar_layout(), warnings, outcome);
  partial.Remove();  // the complete outputs (or the folder as it was) replace it
  // A failed run says one line (the warnings are in summary.json when written).
  if (!written.ok()) return Fail("run", written.message(), written.exit_code());
  if (!read_error.ok())
    return Fail("run", read_error.message() + " (outputs hold the scans read before it)");
  for (const auto& w : warnings) std::fprintf(stderr, "rvlio run: warning: %s\n", w.c_str());
  if (!data.interrupted_by.empty()) return ReportInterrupt(req, data);
  if ((*odo)->divergence().detected)
    return FinishDiverged("run", (*odo)->divergence(), req.out_dir, req.allow_divergence);
  return 0;
}

}  // namespace rvlio::cli
