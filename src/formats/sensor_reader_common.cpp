#include "sensor_reader_common.h"

#include <algorithm>
#include <cstdio>

#include "rvlio/common/median.h"

namespace rvlio::bag_detail {

constexpr double kStandardGravity = 9.80665;  // m/s^2 per g

std::string DescribeTopics(const std::map<std::string, std::string>& topics) {
  std::string out;
  for (const auto& [topic, type] : topics) out += (out.empty() ? "" : ", ") + topic + " (" + type + ")";
  return out.empty() ? "none" : out;
}

Status RequireTopic(const std::string& path, const std::map<std::string, std::string>& topics,
                    const std::string& topic, const std::string& type, const std::string& key) {
  auto it = topics.find(topic);
  if (it == topics.end()) {
    return Status::InvalidInput(key + " '" + topic + "' is not in bag '" + path +
                                "'; topics present: " + DescribeTopics(topics));
  }
  if (it->second != type) {
    return Status::InvalidInput(key + " '" + topic + "' in bag '" + path + "' has type " +
                                it->second + ", expected " + type +
                                "; topics present: " + DescribeTopics(topics));
  }
  return Status::Ok();
}

bool SensorGate::AcceptImu(TimeNs t_ns, const Eigen::Vector3d& acc, const Eigen::Vector3d& gyro,
                           ImuSample* out) {
  const double scale = imu_.accel_unit == "g" ? kStandardGravity : 1.0;
  return AcceptSiImu(t_ns, scale * acc, gyro, out);
}

bool SensorGate::AcceptSiImu(TimeNs t_ns, const Eigen::Vector3d& acc_mps2,
                             const Eigen::Vector3d& gyro, ImuSample* out) {
  ImuSample s;
  s.t_ns = t_ns;
  s.acc_imu = acc_mps2;
  s.gyro_imu = gyro;
  if (!s.acc_imu.allFinite() || !s.gyro_imu.allFinite()) {
    ++stats_.imu_invalid;
    return false;
  }
  if (have_imu_ && !AcceptImuStamp(s.t_ns)) return false;
  have_imu_ = true;
  last_imu_ns_ = s.t_ns;
  ++stats_.imu_samples;
  *out = s;
  return true;
}

namespace {

constexpr size_t kPointTimeCheckScans = 5;  // scans whose point-time spans are judged

}  // namespace

// The per-point times of a sweeping LiDAR span about one scan period. Times
// all zero, or written in milliseconds or microseconds where nanoseconds are
// expected, span 0 or 1e-6..1e-3 of it: the scans could not be deskewed and
// the run would go on quietly with a larger error. Judged once, on the median
// span and the median start-to-start period of the first scans (a single odd
// stamp does not decide it).
Status SensorGate::CheckPointTimes(const Scan& scan) {
  if (first_spans_ns_.size() >= kPointTimeCheckScans) return Status::Ok();
  first_starts_ns_.push_back(scan.t_start_ns);
  first_spans_ns_.push_back(scan.t_end_ns - scan.t_start_ns);
  if (first_spans_ns_.size() < kPointTimeCheckScans) return Status::Ok();
  std::vector<TimeNs> periods_ns;
  for (size_t k = 1; k < first_starts_ns_.size(); ++k)
    if (first_starts_ns_[k] > first_starts_ns_[k - 1])
      periods_ns.push_back(first_starts_ns_[k] - first_starts_ns_[k - 1]);
  if (periods_ns.empty()) return Status::Ok();  // stamps do not advance: judged elsewhere
  const double period_s = NsToSeconds(UpperMedian(periods_ns));
  const double span_s = NsToSeconds(UpperMedian(first_spans_ns_));
  stats_.point_time_span_ratio = span_s / period_s;
  if (stats_.point_time_span_ratio >= lidar_.point_time_span_stop) return Status::Ok();
  char text[400];
  std::snprintf(text, sizeof(text),
                "span %.3g s per scan against a scan period of %.3g s (median of the first %zu "
                "scans): %s, so the scans cannot be deskewed (below lidar.point_time_span_stop "
                "%g of the period; 0 reads anyway)",
                span_s, period_s, kPointTimeCheckScans,
                span_s == 0.0 ? "they are all zero"
                              : "not in nanoseconds (milliseconds or microseconds?)",
                lidar_.point_time_span_stop);
  return Status::InvalidInput("the point times on lidar.topic '" + lidar_.topic + "' in '" +
                              path_ + "' " + text);
}

bool SensorGate::AcceptImuStamp(TimeNs t_ns) {
  if (t_ns == last_imu_ns_) {
    ++stats_.imu_duplicates;
    return false;
  }
  if (t_ns < last_imu_ns_) {
    ++stats_.imu_non_monotonic;
    return false;
  }
  const double gap_s = NsToSeconds(t_ns - last_imu_ns_);
  stats_.imu_max_gap_s = std::max(stats_.imu_max_gap_s, gap_s);
  if (gap_s > imu_.max_gap) ++stats_.imu_gaps;
  return true;
}

StatusOr<bool> SensorGate::AcceptScan(const DecodeStats& decode, Scan&& scan, Scan* out) {
  stats_.invalid_points += decode.invalid_points;
  stats_.out_of_range_points += decode.out_of_range_points;
  if (scan.points.empty()) {
    ++stats_.empty_scans;
    return false;
  }
  if (Status s = CheckPointTimes(scan); !s.ok()) return s;
  ++stats_.scans;
  if (!have_imu_) ++stats_.scans_before_first_imu;
  *out = std::move(scan);
  return true;
}

}  // namespace rvlio::bag_detail
