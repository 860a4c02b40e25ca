#pragma once
// `rvlio run` as a function, so that demo and compare reuse it in-process.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "rvlio/io/sensor_bag.h"
#include "rvlio/io/sensor_stream.h"

namespace rvlio::cli {

struct RunRequest {
  std::string bag;
  std::string out_dir;
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // --set key=value
  bool quiet = false;                  // no progress line even on a terminal
  bool allow_divergence = false;       // exit 0 even if the divergence monitor fired
  ReadWindow window;                   // --start / --duration
};

struct RunOutcome {
  int scans = 0;
  double median_ms = 0.0;
  double real_time_factor = 0.0;
  bool diverged = false;  // the divergence monitor fired (summary.json divergence)
};

// Reads the bag, runs the odometry and writes the outputs of docs/design.md
// section 7. Returns the exit status; errors are printed as one line.
// While it runs, trajectory.partial.tum in the output folder receives each
// pose as it is estimated (removed at an orderly end). Under an InterruptScope
// (interrupt.h) a signal stops the reading: the outputs of the scans done so
// far are written (summary.json "interrupted": true) and the status is 130 /
// 143. Nothing is written when no scan was done. A run the divergence
// monitor flagged writes every output and returns kExitDiverged
// (divergence_cli.h) unless request.allow_divergence.
int RunOdometryOnBag(const RunRequest& request, RunOutcome* outcome);

// Creates `dir` if needed and proves it writable; false with a message if not.
bool PrepareOutputDir(const std::string& command, const std::string& dir);

// The reader's counts of what it skipped or repaired, for summary.json.
nlohmann::json ReaderStatsJson(const SensorReaderStats& stats);

// Peak resident memory of this process, MB.
double PeakMemoryMb();
// Current resident memory of this process, MB (/proc/self/statm; 0 if unknown).
double CurrentMemoryMb();

// A command's outputs are written (each atomically) into a private folder
// inside the output folder and moved into place only when every one of them
// is complete, so a failed write (disk full, file-size limit) leaves the
// output folder exactly as it was: no half file, no mix of old and new.
class OutputStage {
 public:
  explicit OutputStage(std::string out_dir) : out_dir_(std::move(out_dir)) {}
  ~OutputStage();  // removes the staging folder with whatever is left in it
  OutputStage(const OutputStage&) = delete;
  OutputStage& operator=(const OutputStage&) = delete;

  // Creates OUT/.rvlio_stage.<pid>.<random> (mkdtemp: unique per run) and
  // removes staging folders that processes no longer running left behind.
  Status Open();
  // Where to write output `name` (a plain file name); Commit() moves it.
  std::string Path(const std::string& name);
  // Renames every staged file into the output folder.
  Status Commit();
  // A writer's error names the staged file; this one names the output.
  Status Explain(const Status& s) const;

 private:
  std::string out_dir_, stage_dir_;
  std::vector<std::string> names_;
};

// One warning line per kind of input problem the reader skipped or repaired
// (the counts are in summary.json stats.reader).
std::vector<std::string> ReaderWarnings(const SensorReaderStats& stats, const LidarOptions& lidar,
                                        const ImuOptions& imu);

}  // namespace rvlio::cli
