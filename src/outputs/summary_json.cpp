#include "rvlio/outputs/summary_json.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>

#include "rvlio/common/text.h"

namespace rvlio {

std::string ReadFileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

nlohmann::json ReadJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return nullptr;
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? nlohmann::json(nullptr) : j;
}
namespace {

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
          {"imu_max_gap_s", r.imu_max_gap_s},
          {"point_time_span_ratio", r.point_time_span_ratio}};
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
    w.push_back("IMU gaps longer than imu.max_gap " + FormatG(imu.max_gap) + " s" + imu_on + ": " +
                std::to_string(r.imu_gaps) + text);
  }
  if (r.point_time_span_ratio >= 0.0 && r.point_time_span_ratio < lidar.point_time_span_warn) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "the point times%s span %.3g of the scan period (median of the first scans; "
                  "below lidar.point_time_span_warn %g): deskewing corrects only that part of "
                  "the sweep",
                  scans_on.c_str(), r.point_time_span_ratio, lidar.point_time_span_warn);
    w.push_back(text);
  }
  return w;
}

nlohmann::json LocalOriginJson(const LocalOrigin& origin) {
  const Eigen::Vector3d& t = origin.t_user_local;
  return {t.x(), t.y(), t.z()};
}

nlohmann::json DivergenceJson(const DivergenceReport& r) {
  nlohmann::json events = nlohmann::json::object();
  for (int k = 0; k < kNumDivergenceKinds; ++k)
    events[DivergenceKindName(static_cast<DivergenceKind>(k))] = r.episodes[k];
  // Divergence episodes, and the inconsistencies a clock offset explains.
  nlohmann::json episodes = nlohmann::json::array(), inconsistencies = nlohmann::json::array();
  for (const DivergenceEvent& e : r.events) {
    nlohmann::json one = {{"kind", DivergenceKindName(e.kind)},
                          {"time_s", NsToSeconds(e.t_ns)},
                          {"value", e.value},
                          {"threshold", e.threshold},
                          {"still", e.still}};
    if (e.lost) {
      episodes.push_back(one);
      continue;
    }
    one["clock_offset_s"] = e.clock_offset_s;
    one["clock_explained"] = e.clock_explained;
    inconsistencies.push_back(one);
  }
  nlohmann::json j = {
      {"detected", r.detected},
      {"first_time_s", r.detected ? nlohmann::json(NsToSeconds(r.first_t_ns)) : nlohmann::json()},
      {"scans_flagged", r.scans_flagged},
      {"events", events},
      {"episodes", episodes},
      {"inconsistencies", inconsistencies}};
  // Residuals grown with the motion before the divergence, or an
  // inconsistency a clock offset explains: unsynchronized clocks are the
  // likely cause (`rvlio calibrate-time`).
  if (r.detected || r.inconsistencies > 0) j["clock_suspect"] = r.clock_suspect;
  if (std::isfinite(r.clock_offset_s)) j["clock_offset_s"] = r.clock_offset_s;
  return j;
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

}  // namespace rvlio
