#pragma once
// Reading point clouds from PCD and PLY files (docs/map_eval.md "Inputs"):
// a reference survey, an rvlio map.pcd, another tool's map.
//
// PCD (v0.5 - v0.7): DATA ascii, binary and binary_compressed (LZF, the
// fields stored one after another); field types F/I/U of 1, 2, 4 or 8
// bytes. PLY: format ascii, binary_little_endian and binary_big_endian; the
// `vertex` element's scalar properties (elements before it must have no
// list properties; elements after it are not read).
//
// x, y, z (metres) are required. Every other scalar field (COUNT 1, not the
// padding field "_") is kept by name, in file order, as float. The PCD
// VIEWPOINT is not applied (as PCL's readers leave it). The file is only
// read, never written or moved.
//
// Refused, each with one line naming the file: a missing or unreadable
// file, an unknown format, a malformed header, a file shorter than its
// header declares (truncated), a cloud without points, and a cloud with
// non-finite (NaN or inf) coordinates (their count is given).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rvlio/common/status.h"

namespace rvlio {

struct PointCloudField {
  std::string name;
  std::vector<float> values;  // one per point
};

struct PointCloudFile {
  std::vector<Eigen::Vector3d> points;  // x y z, m, the file's frame
  std::vector<PointCloudField> fields;  // other scalar fields, file order
  std::string format;                   // "pcd ascii", "pcd binary", "pcd binary_compressed",
                                        // "ply ascii", "ply binary_little_endian", ...
  // x, y or z is stored as a 4-byte float (binary encodings; an ascii file's
  // numbers have the digits they are written with): far from zero such a
  // cloud is coarse (Float32Step, math/local_origin.h).
  bool xyz_single_precision = false;

  // The field of that name, or nullptr.
  const PointCloudField* Field(const std::string& name) const;
};

struct PointCloudReadOptions {
  bool keep_fields = true;   // false: x y z only (less memory)
  bool allow_empty = false;  // true: a cloud of 0 points is read (an rvlio map.pcd may be one)
};

StatusOr<PointCloudFile> ReadPointCloud(const std::string& path,
                                        const PointCloudReadOptions& options = {});

// A PCD file read in chunks of points, in memory bounded by the chunk (`rvlio
// export` of a map of any size): DATA ascii and binary, the header parsed as
// by ReadPointCloud. Values come as double (no precision lost: an F8 time
// field keeps its nanoseconds). Kept fields as in ReadPointCloud: every
// scalar field (COUNT 1, not "_") other than x, y, z, in file order.
// DATA binary_compressed (its fields are stored one after another, so no
// point is complete before the whole file is read) and PLY are refused with
// a line saying so; ReadPointCloud reads them whole.
struct PointCloudStreamField {
  std::string name;
  char type = 'F';  // PCD TYPE: F (float), I (signed), U (unsigned)
  int size = 4;     // bytes: 1, 2, 4 or 8
};

struct PointCloudChunk {
  std::vector<Eigen::Vector3d> points;       // x y z, m
  std::vector<std::vector<double>> fields;   // per PointCloudStream::fields(), one per point
};

class PointCloudStream {
 public:
  PointCloudStream();
  ~PointCloudStream();
  PointCloudStream(const PointCloudStream&) = delete;
  PointCloudStream& operator=(const PointCloudStream&) = delete;

  // InvalidInput naming the file: missing, unreadable, not a PCD, a
  // malformed header, no x y z, binary_compressed.
  Status Open(const std::string& path);
  const std::vector<PointCloudStreamField>& fields() const;
  int64_t size() const;  // points the header declares
  const std::string& format() const;  // "pcd ascii" or "pcd binary"

  // The next (at most max_points) points into *chunk, replacing its content;
  // returns how many (0 at the end). InvalidInput naming the file and the
  // point for data shorter than the header declares, a value that is not a
  // number (ascii), a non-finite coordinate.
  StatusOr<size_t> Read(size_t max_points, PointCloudChunk* chunk);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rvlio
