// rvlio calibrate-time --bag PATH [--config FILE] [--set K=V]: the LiDAR-IMU
// clock offset of a recording, offline (odometry/clock_check.h), and what the
// stamps alone tell (scan period, jitter, drops, header stamp, IMU rate).
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "common_options.h"
#include "rvlio/config/config.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/formats/sensor_stream.h"
#include "rvlio/lidar/scan_order.h"
#include "rvlio/odometry/clock_check.h"

namespace rvlio::cli {
namespace {

constexpr const char* kCalibrateTime = "calibrate-time";
// A lag below this (and within 3 sigma of zero) counts as synchronized.
constexpr double kSynchronizedS = 0.002;

struct Recording {
  std::vector<ImuSample> imu;
  std::vector<LidarRateSample> rates;
  std::vector<TimeNs> scan_start_ns, scan_end_ns, imu_ns;  // of the scans taken
  int scans_out_of_order = 0, scans_stamp_ahead = 0;       // skipped (lidar/scan_order.h)
};

// The scans in stamp order, as the odometry takes them (lidar/scan_order.h):
// each goes to the tracker one scan late, when the next one shows whether
// its stamp jumped ahead.
class ScreenedScans {
 public:
  ScreenedScans(const OdometryOptions& o, Recording* rec) : tracker_(o), rec_(rec) {}
  void Add(Scan&& scan) {
    const TimeNs imu_end_ns = rec_->imu.empty() ? ScanStampScreen::kNoImu : rec_->imu.back().t_ns;
    switch (screen_.Judge({scan.t_start_ns, scan.t_end_ns}, imu_end_ns)) {
      case StampVerdict::kOutOfOrder: ++rec_->scans_out_of_order; return;
      case StampVerdict::kNewestWereAhead:
        rec_->scans_stamp_ahead += static_cast<int>(screen_.dropped().size());
        has_held_ = false;  // the newest; older ones stamped ahead were tracked already
        break;
      case StampVerdict::kInOrder: break;
    }
    Flush();
    held_ = std::move(scan);
    has_held_ = true;
  }
  void Flush() {
    if (!has_held_) return;
    rec_->scan_start_ns.push_back(held_.t_start_ns);
    rec_->scan_end_ns.push_back(held_.t_end_ns);
    if (std::optional<LidarRateSample> r = tracker_.Add(held_)) rec_->rates.push_back(*r);
    has_held_ = false;
  }

 private:
  ScanRotationTracker tracker_;
  ScanStampScreen screen_;
  Scan held_;
  bool has_held_ = false;
  Recording* rec_;
};

Status Read(const std::string& bag, const Configuration& o, Recording* rec) {
  StatusOr<std::unique_ptr<SensorBagReader>> reader =
      OpenSensorStream(bag, o.lidar, o.imu, ReadWindow(), o.io);
  if (!reader.ok()) return reader.status();
  ScreenedScans scans(o, rec);
  ImuSample imu;
  Scan scan;
  for (;;) {
    StatusOr<SensorMessage> m = (*reader)->Next(&imu, &scan);
    if (!m.ok()) return m.status();
    if (*m == SensorMessage::kEnd) break;
    if (*m == SensorMessage::kImu) {
      rec->imu.push_back(imu);
      rec->imu_ns.push_back(imu.t_ns);
      continue;
    }
    scans.Add(std::move(scan));
  }
  scans.Flush();
  return Status::Ok();
}

std::string HeaderStampLine(const std::string& bag, const std::string& topic) {
  StatusOr<BagInfo> info = ReadBagInfo(bag, topic);
  if (!info.ok()) return "unknown";
  for (const BagTopicInfo& t : info->topics)
    if (t.topic == topic && !t.header_stamp.empty()) return "marks the scan " + t.header_stamp;
  return "not applicable (no PointCloud2 header time layout)";
}

void PrintStamps(const StampReport& s, const Recording& rec, const std::string& header_stamp) {
  std::printf(
      "stamps (no estimation):\n"
      "  lidar: %d scans, period %.2f ms (median), jitter %.3f ms RMS, %d dropped; sweep %.2f ms; "
      "header stamp %s\n",
      s.scans, 1e3 * s.scan_period_s, 1e3 * s.scan_jitter_s, s.dropped_scans,
      1e3 * s.scan_duration_s, header_stamp.c_str());
  if (rec.scans_out_of_order > 0 || rec.scans_stamp_ahead > 0)
    std::printf(
        "         %d more skipped (the gaps they leave count as dropped): %d stamped out of "
        "order (repeating or going back), %d stamped ahead of the scans after them and of the IMU\n",
        rec.scans_out_of_order + rec.scans_stamp_ahead, rec.scans_out_of_order,
        rec.scans_stamp_ahead);
  std::printf(
      "  imu:   %d samples, %.1f Hz, jitter %.3f ms RMS, %d gaps over 2 periods (longest %.2f ms)\n",
      s.imu_samples, s.imu_rate_hz, 1e3 * s.imu_jitter_s, s.imu_gaps, 1e3 * s.imu_max_gap_s);
}

// Why the recording cannot judge the offset, or "" when it can.
std::string CannotJudge(const ClockCheckResult& r, const ClockCheckOptions& c) {
  char text[320];
  switch (r.verdict) {
    case ClockVerdict::kJudged: return "";
    case ClockVerdict::kNoData:
      return "too little data: " + std::to_string(r.intervals) +
             " scan pairs registered inside the gyro's span (3 needed)";
    case ClockVerdict::kNotEnoughRotation:
      std::snprintf(text, sizeof(text), "not enough rotation: gyro rate spread %.3f rad/s (needed: %.3f)",
                    r.rate_spread_rad_s, c.min_rate_spread);
      return text;
    case ClockVerdict::kTooShort:
      std::snprintf(text, sizeof(text),
                    "the recording is too short to judge: %.1f s of rotation (needed: %.1f s)",
                    r.moving_s, c.min_moving_s);
      return text;
    case ClockVerdict::kTooUncertain:
      std::snprintf(text, sizeof(text),
                    "the recording cannot judge the offset: 1-sigma %.2f ms (needed: %.1f ms) over "
                    "%.1f s of rotation",
                    1e3 * r.std_s, 1e3 * c.max_std_s, r.moving_s);
      return text;
  }
  return "";
}

void PrintOffset(const ClockCheckResult& r, const Configuration& o, const ClockCheckOptions& c) {
  std::printf(
      "clock offset (scan-to-scan rotation vs gyroscope, %d intervals, lag searched +-%.0f ms):\n"
      "  rotation excitation: gyro rate spread %.3f rad/s RMS (needed: %.3f), %.1f s rotating "
      "(needed: %.1f)\n",
      r.intervals, 1e3 * c.max_lag_s, r.rate_spread_rad_s, c.min_rate_spread, r.moving_s,
      c.min_moving_s);
  const double offset_s = o.lidar.time_offset + r.lag_s;
  if (const std::string why = CannotJudge(r, c); !why.empty()) {
    if (r.verdict == ClockVerdict::kNoData)
      std::printf("  %s; no offset recommended\n", why.c_str());
    else
      std::printf(
          "  %s; no offset recommended (the best lag, %.1f ms +- %.1f ms, is not to be trusted); "
          "record a few seconds of turning about all axes (or keep lidar.time_offset %.4f s)\n",
          why.c_str(), 1e3 * r.lag_s, 1e3 * r.std_s, o.lidar.time_offset);
    return;
  }
  std::printf(
      "  offset: %.4f s (lidar.time_offset %.4f s + lag %.2f ms), 1-sigma %.2f ms, gyro explains "
      "%.0f %% of the LiDAR rotation rate\n"
      "  -> set lidar.time_offset: %.4f   (t_imu = t_lidar_stamp + time_offset)\n",
      offset_s, o.lidar.time_offset, 1e3 * r.lag_s, 1e3 * r.std_s, 100.0 * r.explained, offset_s);
  if (std::abs(r.lag_s) > 3.0 * r.std_s && std::abs(r.lag_s) > kSynchronizedS)
    std::printf("  the LiDAR and IMU clocks are not synchronized as configured\n");
}

}  // namespace

int CmdCalibrateTime(int argc, char** argv) {
  CommandSpec spec{kCalibrateTime,
                   "Estimates the LiDAR-IMU clock offset of a recording offline: the rotation rate "
                   "from registering consecutive scans is correlated with the gyroscope over a "
                   "range of lags (coarse, then refined). Prints the offset to put in "
                   "lidar.time_offset, its 1-sigma and the rotation excitation seen (or \"not "
                   "enough rotation\"), and what the stamps alone tell: scan period, jitter, "
                   "dropped scans, header stamp at scan start or end, IMU rate and gaps.",
                   {{"bag", "PATH", "ROS1 .bag, ROS 2 .db3, .mcap or bag folder", true},
                    ConfigOption(),
                    SetOption()}};
  Args args;
  if (int rc = Parse(spec, argc, argv, 2, &args); rc != 0) return rc < 0 ? 0 : rc;
  std::vector<std::string> warnings;
  StatusOr<Configuration> o = LoadConfig(args.GetAll("config"), args.GetAll("set"), &warnings);
  if (!o.ok()) return Fail(kCalibrateTime, o.status().message());
  for (const auto& w : warnings) std::fprintf(stderr, "rvlio %s: warning: %s\n", kCalibrateTime, w.c_str());
  Recording rec;
  if (Status s = Read(args.Get("bag"), *o, &rec); !s.ok())
    return Fail(kCalibrateTime, s);
  if (rec.scan_start_ns.empty() || rec.imu.empty())
    return Fail(kCalibrateTime, args.Get("bag") + ": no scans on lidar.topic '" + o->lidar.topic +
                           "' or no IMU samples on imu.topic '" + o->imu.topic + "'");
  std::printf("rvlio %s: %s\n", kCalibrateTime, args.Get("bag").c_str());
  PrintStamps(AnalyzeStamps(rec.scan_start_ns, rec.scan_end_ns, rec.imu_ns), rec,
              HeaderStampLine(args.Get("bag"), o->lidar.topic));
  ClockCheckOptions c;
  c.max_lag_s = o->lidar.time_offset_max;
  PrintOffset(EstimateClockLag(rec.rates, rec.imu, c), *o, c);
  return 0;
}

}  // namespace rvlio::cli
