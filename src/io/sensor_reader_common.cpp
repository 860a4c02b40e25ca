#include "sensor_reader_common.h"

#include <algorithm>

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
  ImuSample s;
  s.t_ns = t_ns;
  const double scale = imu_.accel_unit == "g" ? kStandardGravity : 1.0;
  s.acc_imu = scale * acc;
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

bool SensorGate::AcceptScan(const DecodeStats& decode, Scan&& scan, Scan* out) {
  stats_.invalid_points += decode.invalid_points;
  stats_.out_of_range_points += decode.out_of_range_points;
  if (scan.points.empty()) {
    ++stats_.empty_scans;
    return false;
  }
  ++stats_.scans;
  if (!have_imu_) ++stats_.scans_before_first_imu;
  *out = std::move(scan);
  return true;
}

}  // namespace rvlio::bag_detail
