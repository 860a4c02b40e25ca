#pragma once
// `rvlio run` as a function, so that demo and compare reuse it in-process.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rvlio/io/sensor_bag.h"

namespace rvlio::cli {

struct RunRequest {
  std::string bag;
  std::string out_dir;
  std::vector<std::string> config_files;
  std::vector<std::string> overrides;  // --set key=value
  bool quiet = false;                  // no progress line even on a terminal
};

struct RunOutcome {
  int scans = 0;
  double median_ms = 0.0;
  double real_time_factor = 0.0;
};

// Reads the bag, runs the odometry and writes the outputs of DESIGN.md
// section 6. Returns the exit status; errors are printed as one line.
int RunOdometryOnBag(const RunRequest& request, RunOutcome* outcome);

// Creates `dir` if needed and proves it writable; false with a message if not.
bool PrepareOutputDir(const std::string& command, const std::string& dir);

// The reader's counts of what it skipped or repaired, for summary.json.
nlohmann::json ReaderStatsJson(const SensorReaderStats& stats);

// Peak resident memory of this process, MB.
double PeakMemoryMb();

}  // namespace rvlio::cli
