#pragma once
// The range crop of LiDAR points, [lidar.min_range, lidar.max_range] on the
// squared range: one definition for the two places that apply it.
// - The decoders (formats/pointcloud2.h FilterPoint, Livox, Ouster) drop and
//   count out-of-range points where a recording is read: the reader's
//   out_of_range_points, its empty scans and the "no scans" diagnosis of
//   `rvlio run` come from there, and no scan carries points it cannot use.
// - The scan preprocessor (lidar/preprocess.h) applies the same window to
//   every scan it is given, so scans that a program hands to Odometry
//   directly are cropped too. On a decoded scan it drops nothing more.
#include <limits>

#include "rvlio/lidar/options.h"

namespace rvlio {

class RangeWindow {
 public:
  explicit RangeWindow(const LidarOptions& options)
      : min_range2_m2_(options.min_range * options.min_range),
        max_range2_m2_(options.max_range * options.max_range) {}

  // A finite squared range inside the window; false for NaN and infinity.
  bool Contains(double range2_m2) const {
    return range2_m2 >= min_range2_m2_ && range2_m2 <= max_range2_m2_ &&
           range2_m2 < std::numeric_limits<double>::infinity();
  }

 private:
  double min_range2_m2_;
  double max_range2_m2_;
};

}  // namespace rvlio
