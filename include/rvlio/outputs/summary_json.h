#pragma once
// The pieces of summary.json shared by run, refine, compare and ablate, and
// the process figures they report.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rvlio/imu/options.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/lidar/options.h"
#include "rvlio/math/local_origin.h"
#include "rvlio/odometry/divergence.h"

namespace rvlio {

// JSON text for the outputs. Configuration strings come from the user (--set,
// YAML files, bag topics) and need not be valid UTF-8; nlohmann's default
// dump throws on such bytes, so every output replaces them (U+FFFD).
inline std::string JsonText(const nlohmann::json& j, int indent = 2) {
  return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

// The reader's counts of what it skipped or repaired (summary.json stats.reader).
nlohmann::json ReaderStatsJson(const SensorReaderStats& stats);

// One warning line per kind of input problem the reader skipped or repaired
// (the counts are in summary.json stats.reader).
std::vector<std::string> ReaderWarnings(const SensorReaderStats& stats, const LidarOptions& lidar,
                                        const ImuOptions& imu);

// Reading back what the commands wrote: the whole file as text ("" when it
// cannot be read), and a JSON file (summary.json, cell.json, compare.json,
// plan.json) or null when it is missing, empty or not valid JSON.
std::string ReadFileText(const std::string& path);
nlohmann::json ReadJsonFile(const std::string& path);

// {detected, first_time_s, scans_flagged, events: {kind: episodes}, episodes: [...]}.
nlohmann::json DivergenceJson(const DivergenceReport& report);

// summary.json "local_origin": [x, y, z], m: the offset added to the
// estimation's local frame to give the frame of the outputs (the frame of
// --map or --init; math/local_origin.h). [0, 0, 0] when they coincide.
nlohmann::json LocalOriginJson(const LocalOrigin& origin);

// Peak resident memory of this process, MB.
double PeakMemoryMb();
// Current resident memory of this process, MB (/proc/self/statm; 0 if unknown).
double CurrentMemoryMb();

}  // namespace rvlio
