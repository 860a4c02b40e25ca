#pragma once
// sensor_msgs/NavSatFix (ROS1) and sensor_msgs/msg/NavSatFix (ROS 2, CDR):
// GNSS fixes of a recording (`gnss.topic`, docs/control.md "GNSS").
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/time.h"

namespace rvlio {

inline constexpr const char* kNavSatFixRos1Type = "sensor_msgs/NavSatFix";
inline constexpr const char* kNavSatFixRos2Type = "sensor_msgs/msg/NavSatFix";

struct NavSatFix {
  TimeNs header_stamp_ns = 0;
  std::string frame_id;
  int8_t status = 0;  // -1 no fix, 0 fix, 1 SBAS, 2 GBAS (RTK)
  uint16_t service = 1;  // GPS
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;  // WGS 84, ellipsoidal height
  std::array<double, 9> position_covariance{};  // m^2, ENU, row-major
  uint8_t covariance_type = 0;  // 0 unknown, 1 approximated, 2 diagonal known, 3 known
};
inline constexpr int8_t kNavSatStatusNoFix = -1;

// One message's bytes (ROS1 wire format / CDR with its encapsulation header).
StatusOr<NavSatFix> ParseRos1NavSatFix(const uint8_t* data, size_t size, const std::string& where);
StatusOr<NavSatFix> DecodeNavSatFixCdr(const uint8_t* data, size_t size, const std::string& where);
std::vector<uint8_t> EncodeNavSatFixCdr(const NavSatFix& fix);

struct NavSatFixStats {
  int64_t messages = 0;
  int64_t no_fix = 0;  // status -1 or a non-finite position: skipped
};

// Every message of `topic` (a NavSatFix topic) in receive order; fixes
// without a solution are skipped and counted. InvalidInput naming the topic
// and the recording for a missing topic or another type, a corrupt message,
// or a latitude outside [-90, 90] / longitude outside [-180, 180] (naming the
// message's index and stamp).
StatusOr<std::vector<NavSatFix>> ReadNavSatFixes(const std::string& path, const std::string& topic,
                                                 NavSatFixStats* stats);

}  // namespace rvlio
