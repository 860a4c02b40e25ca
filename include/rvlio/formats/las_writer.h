#pragma once
// A streaming writer of ASPRS LAS 1.4 (R15) files, point data record format 6
// (docs/outputs.md "map.las" describes every field). Points are encoded as
// they come and written through formats/atomic_file.h, so any number of
// points takes bounded memory, and the file appears at Commit(), complete, or
// not at all. The public header's counts and bounds (and the extra-bytes
// minima and maxima) are known only at the end: Commit() writes them over the
// provisional header (its counts and bounds zero).
//
// What the writer fixes (the caller cannot get them wrong):
//  - X, Y, Z: scaled integers, scale 0.001 m, the offset a multiple of 1 km
//    (options.offset_m, or the first point rounded down to one), so every
//    coordinate is stored to the millimetre of the CRS. A point farther than
//    the 32-bit range (2147 km) from the offset is refused (InvalidInput).
//    The header's bounds are those of the stored (rounded) coordinates.
//  - GPS time: Adjusted Standard GPS Time (global encoding bit 0 set):
//    rvlio's times are UNIX seconds (UTC) of the recording; GPS time adds the
//    leap seconds since 1980-01-06 (18 since 2017) and is written minus 1e9.
//  - Return number 1 of 1, classification 0 (never classified), scan angle 0,
//    file source ID 0; point source ID: the scan index modulo 65536 when the
//    caller gives one (has_point_source), else 0.
//  - WKT (global encoding bit 4) is set, as point format 6 requires; the CRS is
//    an OGC coordinate system WKT VLR (LASF_Projection 2112) when one is given.
//  - Extra bytes (LASF_Spec 4) describe the per-point attributes after the 30
//    bytes of format 6; a float attribute's NaN is stored as NaN and declared
//    as its no_data value; min and max are those of the finite values.
//  - A text area description VLR (LASF_Spec 3) states these conventions and
//    the intensity scale in words, for the person who opens the file.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"
#include "rvlio/formats/atomic_file.h"

namespace rvlio {

// The Extra Bytes data_type codes of the LAS 1.4 specification (1-10).
enum class LasScalar : uint8_t {
  kUint8 = 1, kInt8 = 2, kUint16 = 3, kInt16 = 4, kUint32 = 5, kInt32 = 6,
  kUint64 = 7, kInt64 = 8, kFloat = 9, kDouble = 10,
};
// Bytes of one value of the type.
int LasScalarSize(LasScalar type);

struct LasExtraField {
  std::string name;         // 1-32 characters, unique
  LasScalar type = LasScalar::kFloat;
  std::string description;  // at most 32 characters
};

struct LasWriterOptions {
  // X, Y, Z offset (m). Must be a multiple of 0.001 m to keep the millimetre
  // grid of the CRS; nullopt: the first point rounded down to a multiple of
  // 1000 m (0 when no point is written).
  std::optional<Eigen::Vector3d> offset_m;
  std::string crs_wkt;  // OGC WKT of the coordinate system; empty: no CRS VLR (a local frame)
  // LAS intensity = round(intensity * intensity_scale), clamped to 0..65535;
  // 0: the points have no intensity (0 is written, as the specification asks).
  double intensity_scale = 0.0;
  std::string intensity_source;  // what the intensity was (e.g. "intensity, 8 bit"), for the description
  bool has_time = false;  // LasPoint::unix_time_s holds the acquisition time (else GPS time 0)
  bool has_ring = false;  // LasPoint::ring goes to User Data (else 0)
  bool has_point_source = false;  // LasPoint::scan_index goes to Point Source ID (else 0)
  std::vector<LasExtraField> extra_fields;  // LasPoint::extra, in this order
  std::string system_identifier = "rvlio lidar-inertial map";  // at most 32 characters
  std::string generating_software;  // default "rvlio VERSION"
};

struct LasPoint {
  Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
  double intensity = 0.0;    // the sensor's unit
  double unix_time_s = 0.0;  // acquisition time, UNIX seconds (UTC)
  int ring = 0;              // beam; 0..255 (User Data), larger saturate at 255
  uint64_t scan_index = 0;   // Point Source ID: modulo 65536 (16 bits)
  const double* extra = nullptr;  // one value per extra field (NaN allowed for floats)
};

struct LasWriteStats {
  uint64_t points = 0;
  uint64_t intensity_clamped = 0;  // values outside 0..65535 after scaling
  uint64_t ring_saturated = 0;     // rings outside 0..255
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero(), max_m = Eigen::Vector3d::Zero();
};

class LasWriter {
 public:
  // Checks the options (InvalidInput naming what is wrong) and writes the
  // provisional header (its counts and bounds zero); the file appears only at Commit().
  Status Open(const std::string& path, LasWriterOptions options);
  // InvalidInput for a non-finite coordinate or one outside the 32-bit range
  // around the offset; the writer is then discarded.
  Status Write(const LasPoint& point);
  // The final header, then fsync and rename: the file appears now.
  Status Commit();
  // Drops the temporary file (also what destruction without Commit does).
  void Discard();

  const LasWriteStats& stats() const { return stats_; }
  static constexpr double kScale_m = 0.001;
  static constexpr uint16_t kHeaderSize = 375;
  static constexpr uint16_t kFormat6Size = 30;

 private:
  Status Fail(Status s);
  std::string Header() const;
  std::string Vlrs() const;
  std::string Description() const;
  void SetOffset(const Eigen::Vector3d& first_m);

  AtomicFileWriter file_;
  LasWriterOptions options_;
  std::string path_;
  uint16_t record_size_ = kFormat6Size;
  uint32_t point_offset_ = 0;  // offset to point data
  bool offset_set_ = false;
  std::string record_;  // one encoded point
  Eigen::Matrix<int64_t, 3, 1> min_i_, max_i_;  // stored integer bounds
  std::vector<double> extra_min_, extra_max_;   // finite values of each extra field
  LasWriteStats stats_;
};

// Adjusted Standard GPS Time (GPS seconds since 1980-01-06 minus 1e9) of a
// UNIX time (UTC seconds), with the leap seconds in force then.
double UnixToAdjustedGpsTime(double unix_s);

}  // namespace rvlio
