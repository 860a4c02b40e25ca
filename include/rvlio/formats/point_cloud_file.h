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

}  // namespace rvlio
