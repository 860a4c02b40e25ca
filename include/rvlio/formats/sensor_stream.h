#pragma once
// The one way the commands open a recording: SensorBagReader::Open (any
// storage kind) wrapped so that
//   - lidar.time_offset moves every scan onto the IMU clock
//     (t_imu_clock = t_lidar_stamp + time_offset: point times, t_start_ns, t_end_ns),
//   - a time window (--start / --duration) selects part of the recording,
//   - reading and decoding run on a thread of their own feeding a bounded
//     queue (io.reader_thread), with the same messages, stats and errors, in
//     the same order, as inline reading.
#include <memory>
#include <string>

#include "rvlio/common/status.h"
#include "rvlio/imu/options.h"
#include "rvlio/formats/reader_options.h"
#include "rvlio/formats/sensor_bag.h"
#include "rvlio/lidar/options.h"

namespace rvlio {

// Part of a recording, in seconds from its first delivered message (IMU
// stamp or scan end, after the time offset). A scan is in the window when its
// t_end_ns is; IMU samples are delivered from kImuLeadInS before the window
// start so that the first scan in it is covered.
struct ReadWindow {
  double start_s = 0.0;     // >= 0
  double duration_s = 0.0;  // > 0; 0: to the end of the recording
};
inline constexpr double kImuLeadInS = 1.0;

// The part of a recording spanning [start_s, end_s] (s, its first and last
// message) that `window` asks for, [first, last]: from start_s +
// window.start_s to window.duration_s later, or to end_s when that comes
// first. What a progress line counts against.
struct WindowSpan {
  double first_s = 0.0, last_s = 0.0;
};
WindowSpan SpanOfWindow(double start_s, double end_s, const ReadWindow& window);

// Opens `path`. InvalidInput for everything SensorBagReader::Open rejects, a
// negative start or duration, and a start at or past the end of the recording
// (one line naming the recording, its length and the start). stats() counts
// the scans and IMU samples delivered; the drop counts cover all that was read.
StatusOr<std::unique_ptr<SensorBagReader>> OpenSensorStream(const std::string& path,
                                                            const LidarOptions& lidar,
                                                            const ImuOptions& imu,
                                                            const ReadWindow& window,
                                                            const ReaderOptions& io);

}  // namespace rvlio
