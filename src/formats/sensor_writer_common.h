#pragma once
// Private, ROS-free pieces shared by the ROS1 and ROS 2 sensor writers
// (src/formats only): the Ouster driver cloud layout and stamp checks.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rvlio/common/status.h"
#include "rvlio/common/types.h"
#include "rvlio/formats/pointcloud2.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio::bag_detail {

// A PointCloud2 that owns its bytes (view.data points into data).
struct OwnedCloud {
  PointCloud2View view;
  std::vector<uint8_t> data;
  bool is_dense = false;
};

// The Ouster driver layout of SensorBagWriter::WriteOusterScan, without the
// header stamp (set by the caller). InvalidInput for a point whose time does
// not fit the uint32 ns field.
Status BuildOusterCloud(const Scan& scan, int rows, int cols, OwnedCloud* out);

// Time of point `index` in ns from the scan start, as the uint32 relative
// time fields (Ouster `t`, Livox `offset_time`) hold it. A no-return (zero)
// point keeps whatever time it has when it fits, else 0; InvalidInput for any
// other point more than 4.29 s from the start.
Status RelativePointTime(const Scan& scan, const LidarPoint& p, size_t index, uint32_t* t);

// Checks every point of a scan with RelativePointTime.
Status CheckRelativePointTimes(const Scan& scan);

// InvalidInput unless 0 <= t_ns <= max_ns ("... outside the <range_text>").
Status CheckStamp(TimeNs t_ns, TimeNs max_ns, const std::string& range_text,
                  const std::string& what);

// The ROS 2 writers (options.format "mcap" or "db3"); ros2_sensor_writer.cpp.
StatusOr<std::unique_ptr<SensorBagWriter>> CreateRos2Writer(const std::string& path,
                                                            const BagWriterOptions& options);

}  // namespace rvlio::bag_detail
