// libFuzzer target: sensor_msgs/PointCloud2 decoding (formats/pointcloud2.h), the
// entry points the bag reader calls (DetectPointCloud2Layout at open,
// DecodePointCloud2 per message), on a message built from the fuzz bytes;
// every decoded scan is also compared with DecodePointCloud2Generic's.
//
// Input layout (FuzzedDataProvider; fuzz/make_seeds.py writes the same):
// integers are taken from the END of the input in this order
//   type (0..5), header_stamp (0..2), min_range cm (0..1000),
//   max_range - min_range cm (1..100000), header stamp (int64),
//   is_bigendian (bool), consistent (bool), field count (0..12), then per
//   field: name pick (uint8: < kNames size picks a known name, else a string
//   is taken from the front), offset, datatype (uint8), count, then
//   consistent: height (1..4), padding (0..8); else height, width,
//   point_step, row_step (uint32 each);
// and the point data is what remains at the FRONT. In the consistent mode
// offsets/counts are small and width, point_step and row_step follow from the
// fields and the data size, so most inputs reach the point loop.
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "rvlio/formats/pointcloud2.h"

namespace {

using rvlio::DecodeStats;
using rvlio::PointCloud2View;
using rvlio::PointField;
using rvlio::Scan;

const char* const kTypes[] = {"auto", "ouster", "velodyne", "hesai", "livox", "bogus"};
const char* const kStamps[] = {"auto", "start", "end"};
const char* const kNames[] = {"x",    "y",           "z",    "intensity", "ring",
                              "t",    "time",        "timestamp", "offset_time", "line",
                              "tag",  "reflectivity", "ambient", "range"};
constexpr size_t kNameCount = sizeof(kNames) / sizeof(kNames[0]);

[[noreturn]] void Fail(const char* what) {
  std::fprintf(stderr, "pointcloud2 fuzzer invariant violated: %s\n", what);
  std::abort();
}
void Require(bool ok, const char* what) {
  if (!ok) Fail(what);
}

bool IsKnownLayout(const std::string& s) {
  return s == "ouster" || s == "velodyne" || s == "hesai" || s == "livox";
}

PointField ConsumeField(FuzzedDataProvider& fdp, bool consistent) {
  PointField f;
  const uint8_t pick = fdp.ConsumeIntegral<uint8_t>();
  f.name = pick < kNameCount ? kNames[pick] : fdp.ConsumeRandomLengthString(32);
  if (consistent) {
    f.offset = fdp.ConsumeIntegralInRange<uint32_t>(0, 64);
    f.datatype = static_cast<uint8_t>(fdp.ConsumeIntegralInRange<int>(1, 8));
    f.count = fdp.ConsumeIntegralInRange<uint32_t>(0, 2);
  } else {
    f.offset = fdp.ConsumeIntegral<uint32_t>();
    f.datatype = fdp.ConsumeIntegral<uint8_t>();
    f.count = fdp.ConsumeIntegral<uint32_t>();
  }
  return f;
}

// Bytes that every field needs from the start of a point.
uint32_t FieldsEnd(const std::vector<PointField>& fields) {
  uint64_t end = 0;
  for (const auto& f : fields)
    end = std::max<uint64_t>(end, uint64_t{f.offset} + rvlio::PointFieldSize(f.datatype) *
                                                          std::max<uint32_t>(f.count, 1));
  return static_cast<uint32_t>(std::min<uint64_t>(end, UINT32_MAX));
}

void CheckScan(const PointCloud2View& cloud, const rvlio::LidarOptions& lidar, const Scan& scan,
               const DecodeStats& stats) {
  const int64_t raw = static_cast<int64_t>(uint64_t{cloud.height} * cloud.width);
  Require(stats.raw_points == raw, "raw_points != height * width");
  Require(static_cast<int64_t>(scan.points.size()) <= raw, "more points than height * width");
  Require(static_cast<int64_t>(scan.points.size()) + stats.invalid_points +
                  stats.out_of_range_points == raw,
          "kept + invalid + out of range != raw points");
  Require(IsKnownLayout(stats.layout), "unknown layout name");
  Require(scan.t_start_ns <= scan.t_end_ns, "t_start > t_end");
  if (scan.points.empty())
    Require(scan.t_start_ns == cloud.header_stamp_ns && scan.t_end_ns == cloud.header_stamp_ns,
            "empty scan not stamped with the header");
  const double lo = lidar.min_range * (1.0 - 1e-5), hi = lidar.max_range * (1.0 + 1e-5);
  for (const auto& p : scan.points) {
    Require(p.p_lidar.allFinite(), "non-finite point");
    Require(std::isfinite(p.intensity), "non-finite intensity");
    const double r = p.p_lidar.cast<double>().norm();
    Require(r > 0.0 && r >= lo && r <= hi, "point outside [min_range, max_range]");
    Require(p.t_ns >= scan.t_start_ns && p.t_ns <= scan.t_end_ns, "point time outside the scan");
  }
}

bool SameScan(const Scan& a, const Scan& b) {
  if (a.points.size() != b.points.size() || a.t_start_ns != b.t_start_ns ||
      a.t_end_ns != b.t_end_ns)
    return false;
  for (size_t i = 0; i < a.points.size(); ++i) {
    const rvlio::LidarPoint& p = a.points[i];
    const rvlio::LidarPoint& q = b.points[i];
    if (std::memcmp(p.p_lidar.data(), q.p_lidar.data(), 3 * sizeof(float)) != 0 ||
        std::memcmp(&p.intensity, &q.intensity, sizeof(float)) != 0 || p.t_ns != q.t_ns ||
        p.ring != q.ring)
      return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider fdp(data, size);
  rvlio::LidarOptions lidar;
  lidar.type = kTypes[fdp.ConsumeIntegralInRange<int>(0, 5)];
  lidar.header_stamp = kStamps[fdp.ConsumeIntegralInRange<int>(0, 2)];
  lidar.min_range = fdp.ConsumeIntegralInRange<int>(0, 1000) * 0.01;
  lidar.max_range = lidar.min_range + fdp.ConsumeIntegralInRange<int>(1, 100000) * 0.01;

  PointCloud2View cloud;
  cloud.topic = "/fuzz";
  cloud.header_stamp_ns = fdp.ConsumeIntegral<int64_t>();
  cloud.is_bigendian = fdp.ConsumeBool();
  const bool consistent = fdp.ConsumeBool();
  const int n_fields = fdp.ConsumeIntegralInRange<int>(0, 12);
  for (int i = 0; i < n_fields; ++i) cloud.fields.push_back(ConsumeField(fdp, consistent));
  uint32_t height = 0, padding = 0;
  if (consistent) {
    height = fdp.ConsumeIntegralInRange<uint32_t>(1, 4);
    padding = fdp.ConsumeIntegralInRange<uint32_t>(0, 8);
  } else {
    cloud.height = fdp.ConsumeIntegral<uint32_t>();
    cloud.width = fdp.ConsumeIntegral<uint32_t>();
    cloud.point_step = fdp.ConsumeIntegral<uint32_t>();
    cloud.row_step = fdp.ConsumeIntegral<uint32_t>();
  }
  // An exact-size copy, so that ASan sees any read past the message.
  const std::vector<uint8_t> bytes = fdp.ConsumeRemainingBytes<uint8_t>();
  cloud.data = bytes.empty() ? nullptr : bytes.data();
  cloud.data_size = bytes.size();
  if (consistent) {
    cloud.height = height;
    cloud.point_step = FieldsEnd(cloud.fields) + padding;
    const size_t row_bytes = bytes.size() / height;
    cloud.width = cloud.point_step == 0 ? 0 : static_cast<uint32_t>(row_bytes / cloud.point_step);
    cloud.row_step = static_cast<uint32_t>(row_bytes);
  }

  const rvlio::StatusOr<std::string> detected = rvlio::DetectPointCloud2Layout(cloud, lidar.type);
  if (detected.ok()) Require(IsKnownLayout(*detected), "detected an unknown layout");
  else Require(!detected.status().message().empty(), "empty error message");

  DecodeStats stats;
  const rvlio::StatusOr<Scan> scan = rvlio::DecodePointCloud2(cloud, lidar, &stats);
#ifdef RVLIO_FUZZ_VERBOSE  // seed checks: what an input decodes to
  std::fprintf(stderr, "%ux%u step %u: %s layout %s kept %zu invalid %lld\n", cloud.height,
               cloud.width, cloud.point_step,
               scan.ok() ? "ok" : scan.status().message().c_str(), stats.layout.c_str(),
               scan.ok() ? scan->points.size() : 0, static_cast<long long>(stats.invalid_points));
#endif
  if (!scan.ok()) {
    Require(scan.status().code() == rvlio::StatusCode::kInvalidInput, "error is not InvalidInput");
    Require(!scan.status().message().empty(), "empty error message");
    return 0;
  }
  CheckScan(cloud, lidar, *scan, stats);
  // The bag reader detects the layout at open, then decodes every message
  // with lidar.type: both must agree.
  Require(detected.ok() && *detected == stats.layout, "detected layout != decoded layout");
  if (lidar.type != "auto") Require(stats.layout == lidar.type, "layout != lidar.type");
  // Decoding again with the detected layout named explicitly gives the same scan.
  rvlio::LidarOptions named = lidar;
  named.type = stats.layout;
  const rvlio::StatusOr<Scan> again = rvlio::DecodePointCloud2(cloud, named, nullptr);
  Require(again.ok() && again->points.size() == scan->points.size() &&
              again->t_start_ns == scan->t_start_ns && again->t_end_ns == scan->t_end_ns,
          "explicit layout decodes differently from auto");
  // The fast path of the common layouts and the generic reader agree bit for bit.
  DecodeStats generic_stats;
  const rvlio::StatusOr<Scan> generic = rvlio::DecodePointCloud2Generic(cloud, lidar, &generic_stats);
  Require(generic.ok(), "generic reader rejects what the fast path decodes");
  Require(SameScan(*scan, *generic), "fast path and generic reader decode different scans");
  Require(stats.invalid_points == generic_stats.invalid_points &&
              stats.out_of_range_points == generic_stats.out_of_range_points &&
              stats.stamp_is_end == generic_stats.stamp_is_end,
          "fast path and generic reader count differently");
  return 0;
}
