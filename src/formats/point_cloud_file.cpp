#include "rvlio/formats/point_cloud_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "rvlio/common/memory.h"

namespace rvlio {

const PointCloudField* PointCloudFile::Field(const std::string& name) const {
  for (const PointCloudField& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

// The record layout of a file: named (not in the unnamed namespace below)
// because PointCloudStream::Impl holds one.
namespace point_cloud_layout {

enum class ScalarKind { kFloat, kInt, kUint };

// One field of a point record: `count` scalars of `size` bytes at `offset`.
struct FieldLayout {
  std::string name;
  ScalarKind kind = ScalarKind::kFloat;
  int size = 4;
  int count = 1;
  size_t offset = 0;      // bytes from the record's start (binary)
  size_t first_scalar = 0;  // index of its first scalar in the record (ascii)
};

struct FileLayout {
  std::vector<FieldLayout> fields;
  size_t record_bytes = 0;
  size_t record_scalars = 0;
  bool big_endian = false;
  int64_t num_points = 0;
};

// Which fields become x, y, z and which are kept.
struct FieldPlan {
  int x = -1, y = -1, z = -1;
  std::vector<int> kept;  // indices into layout.fields
};

}  // namespace point_cloud_layout

namespace {

using namespace point_cloud_layout;  // NOLINT: this file's own types

struct Body {
  const char* data = nullptr;  // first byte after the header
  size_t size = 0;
};

std::vector<std::string> Split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

// Reads the next header line (without '\r\n') from text at *pos; false at the end.
bool NextLine(const std::string& text, size_t* pos, std::string* line) {
  if (*pos >= text.size()) return false;
  size_t end = text.find('\n', *pos);
  const bool last = end == std::string::npos;
  if (last) end = text.size();
  *line = text.substr(*pos, end - *pos);
  if (!line->empty() && line->back() == '\r') line->pop_back();
  *pos = last ? text.size() : end + 1;
  return true;
}

bool ParseInt64(const std::string& s, int64_t* out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (errno != 0 || *end != '\0') return false;
  *out = v;
  return true;
}

void FinishLayout(FileLayout* layout) {
  size_t offset = 0, scalars = 0;
  for (FieldLayout& f : layout->fields) {
    f.offset = offset;
    f.first_scalar = scalars;
    offset += static_cast<size_t>(f.size) * f.count;
    scalars += f.count;
  }
  layout->record_bytes = offset;
  layout->record_scalars = scalars;
}

// ------------------------------------------------------------------- PCD

Status PcdError(const std::string& path, const std::string& what) {
  return Status::InvalidInput(path + ": malformed PCD header: " + what);
}

// Parses the header up to and including the DATA line; *data_kind is ascii,
// binary or binary_compressed; *body_pos the first byte after the header.
Status ParsePcdHeader(const std::string& path, const std::string& text, FileLayout* layout,
                      std::string* data_kind, size_t* body_pos) {
  std::vector<std::string> names, sizes, types, counts;
  int64_t width = -1, height = 1, points = -1;
  size_t pos = 0;
  std::string line;
  while (NextLine(text, &pos, &line)) {
    const std::vector<std::string> w = Split(line);
    if (w.empty() || w[0][0] == '#') continue;
    const std::vector<std::string> values(w.begin() + 1, w.end());
    const std::string& key = w[0];
    if (key == "VERSION" || key == "VIEWPOINT") continue;
    if (key == "FIELDS" || key == "COLUMNS") names = values;
    else if (key == "SIZE") sizes = values;
    else if (key == "TYPE") types = values;
    else if (key == "COUNT") counts = values;
    else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      int64_t v = 0;
      if (values.size() != 1 || !ParseInt64(values[0], &v) || v < 0)
        return PcdError(path, key + " is not a non-negative integer");
      (key == "WIDTH" ? width : key == "HEIGHT" ? height : points) = v;
    } else if (key == "DATA") {
      if (values.size() != 1) return PcdError(path, "DATA needs one word");
      *data_kind = values[0];
      *body_pos = pos;
      break;
    } else {
      return PcdError(path, "unknown header line '" + line.substr(0, 40) + "'");
    }
  }
  if (data_kind->empty()) return PcdError(path, "no DATA line");
  if (*data_kind != "ascii" && *data_kind != "binary" && *data_kind != "binary_compressed")
    return PcdError(path, "DATA " + *data_kind + " (ascii, binary or binary_compressed expected)");
  if (names.empty()) return PcdError(path, "no FIELDS line");
  if (counts.empty()) counts.assign(names.size(), "1");
  if (types.empty() && *data_kind == "ascii") types.assign(names.size(), "F");
  if (sizes.empty() && *data_kind == "ascii") sizes.assign(names.size(), "4");
  if (sizes.size() != names.size() || types.size() != names.size() ||
      counts.size() != names.size())
    return PcdError(path, "FIELDS, SIZE, TYPE and COUNT differ in length");
  for (size_t i = 0; i < names.size(); ++i) {
    FieldLayout f;
    f.name = names[i];
    int64_t size = 0, count = 0;
    if (!ParseInt64(sizes[i], &size) || !ParseInt64(counts[i], &count) || count < 1)
      return PcdError(path, "bad SIZE or COUNT of field " + f.name);
    f.size = static_cast<int>(size);
    f.count = static_cast<int>(count);
    const std::string& t = types[i];
    if (t == "F" && (size == 4 || size == 8)) f.kind = ScalarKind::kFloat;
    else if (t == "I" && (size == 1 || size == 2 || size == 4 || size == 8)) f.kind = ScalarKind::kInt;
    else if (t == "U" && (size == 1 || size == 2 || size == 4 || size == 8)) f.kind = ScalarKind::kUint;
    else return PcdError(path, "field " + f.name + " has TYPE " + t + " SIZE " + sizes[i]);
    layout->fields.push_back(f);
  }
  if (width >= 0 && height > 0 && width > std::numeric_limits<int64_t>::max() / height)
    return PcdError(path, "WIDTH x HEIGHT overflows");
  if (points < 0) {
    if (width < 0) return PcdError(path, "neither POINTS nor WIDTH");
    points = width * height;
  } else if (width >= 0 && width * height != points) {
    return PcdError(path, "WIDTH x HEIGHT = " + std::to_string(width * height) +
                              " but POINTS = " + std::to_string(points));
  }
  layout->num_points = points;
  FinishLayout(layout);
  return Status::Ok();
}

// LZF decompression (the format of liblzf's lzf_d.c, which PCL uses for
// binary_compressed). False on corrupt input or a size mismatch.
bool LzfDecompress(const uint8_t* in, size_t in_size, uint8_t* out, size_t out_size) {
  const uint8_t* ip = in;
  const uint8_t* const in_end = in + in_size;
  uint8_t* op = out;
  uint8_t* const out_end = out + out_size;
  while (ip < in_end) {
    size_t ctrl = *ip++;
    if (ctrl < 32) {  // literal run of ctrl + 1 bytes
      ++ctrl;
      if (static_cast<size_t>(out_end - op) < ctrl || static_cast<size_t>(in_end - ip) < ctrl)
        return false;
      std::memcpy(op, ip, ctrl);
      op += ctrl;
      ip += ctrl;
    } else {  // back reference
      size_t len = ctrl >> 5;
      if (ip >= in_end) return false;
      if (len == 7) {
        len += *ip++;
        if (ip >= in_end) return false;
      }
      const size_t back = ((ctrl & 0x1f) << 8) + *ip++ + 1;
      if (static_cast<size_t>(op - out) < back) return false;
      if (static_cast<size_t>(out_end - op) < len + 2) return false;
      const uint8_t* ref = op - back;
      for (size_t i = 0; i < len + 2; ++i) *op++ = *ref++;  // may overlap: byte by byte
    }
  }
  return op == out_end;
}

// binary_compressed: two uint32 (compressed, uncompressed size), the LZF
// data, which decompresses to each field's values for all points in turn;
// re-interleaved into point records.
Status DecompressPcd(const std::string& path, const Body& body, const FileLayout& layout,
                     std::string* records) {
  if (body.size < 8) return Status::InvalidInput(path + ": truncated (no compressed data)");
  uint32_t compressed = 0, uncompressed = 0;
  std::memcpy(&compressed, body.data, 4);
  std::memcpy(&uncompressed, body.data + 4, 4);
  const uint64_t expected = static_cast<uint64_t>(layout.num_points) * layout.record_bytes;
  if (uncompressed != expected)
    return Status::InvalidInput(path + ": compressed data holds " + std::to_string(uncompressed) +
                                " bytes, the header declares " + std::to_string(expected));
  if (body.size - 8 < compressed)
    return Status::InvalidInput(path + ": truncated: " + std::to_string(compressed) +
                                " compressed bytes declared, " + std::to_string(body.size - 8) +
                                " present");
  std::string fieldwise(uncompressed, '\0');
  if (uncompressed > 0 &&
      !LzfDecompress(reinterpret_cast<const uint8_t*>(body.data + 8), compressed,
                     reinterpret_cast<uint8_t*>(&fieldwise[0]), uncompressed))
    return Status::InvalidInput(path + ": corrupt compressed data");
  records->assign(uncompressed, '\0');
  const size_t n = static_cast<size_t>(layout.num_points);
  size_t block = 0;
  for (const FieldLayout& f : layout.fields) {
    const size_t bytes = static_cast<size_t>(f.size) * f.count;
    for (size_t i = 0; i < n; ++i)
      std::memcpy(&(*records)[i * layout.record_bytes + f.offset], &fieldwise[block + i * bytes],
                  bytes);
    block += n * bytes;
  }
  return Status::Ok();
}

// ------------------------------------------------------------------- PLY

Status PlyError(const std::string& path, const std::string& what) {
  return Status::InvalidInput(path + ": malformed PLY header: " + what);
}

bool PlyType(const std::string& t, ScalarKind* kind, int* size) {
  struct Entry { const char* name; ScalarKind kind; int size; };
  static const Entry kTypes[] = {
      {"char", ScalarKind::kInt, 1},     {"int8", ScalarKind::kInt, 1},
      {"uchar", ScalarKind::kUint, 1},   {"uint8", ScalarKind::kUint, 1},
      {"short", ScalarKind::kInt, 2},    {"int16", ScalarKind::kInt, 2},
      {"ushort", ScalarKind::kUint, 2},  {"uint16", ScalarKind::kUint, 2},
      {"int", ScalarKind::kInt, 4},      {"int32", ScalarKind::kInt, 4},
      {"uint", ScalarKind::kUint, 4},    {"uint32", ScalarKind::kUint, 4},
      {"float", ScalarKind::kFloat, 4},  {"float32", ScalarKind::kFloat, 4},
      {"double", ScalarKind::kFloat, 8}, {"float64", ScalarKind::kFloat, 8}};
  for (const Entry& e : kTypes)
    if (t == e.name) {
      *kind = e.kind;
      *size = e.size;
      return true;
    }
  return false;
}

// An element of the header: its count, scalar layout, and whether it has a
// list property (whose records then have no fixed size).
struct PlyElement {
  std::string name;
  int64_t count = 0;
  FileLayout layout;
  bool has_list = false;
};

// Parses the header; *layout is the vertex element's, *skip_records the
// elements before it (records to skip: bytes for binary, lines for ascii).
Status ParsePlyHeader(const std::string& path, const std::string& text, FileLayout* layout,
                      std::string* format, int64_t* skip_bytes, int64_t* skip_lines,
                      size_t* body_pos) {
  size_t pos = 0;
  std::string line;
  NextLine(text, &pos, &line);  // "ply"
  std::vector<PlyElement> elements;
  bool ended = false;
  while (NextLine(text, &pos, &line)) {
    const std::vector<std::string> w = Split(line);
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "format") {
      if (w.size() < 2) return PlyError(path, "format line");
      *format = w[1];
    } else if (w[0] == "element") {
      PlyElement e;
      if (w.size() != 3 || !ParseInt64(w[2], &e.count) || e.count < 0)
        return PlyError(path, "element line '" + line.substr(0, 40) + "'");
      e.name = w[1];
      elements.push_back(e);
    } else if (w[0] == "property") {
      if (elements.empty()) return PlyError(path, "property before any element");
      if (w.size() >= 2 && w[1] == "list") {
        elements.back().has_list = true;
        continue;
      }
      FieldLayout f;
      if (w.size() != 3 || !PlyType(w[1], &f.kind, &f.size))
        return PlyError(path, "property line '" + line.substr(0, 40) + "'");
      f.name = w[2];
      elements.back().layout.fields.push_back(f);
    } else if (w[0] == "end_header") {
      ended = true;
      break;
    } else {
      return PlyError(path, "unknown line '" + line.substr(0, 40) + "'");
    }
  }
  if (!ended) return PlyError(path, "no end_header");
  if (*format != "ascii" && *format != "binary_little_endian" && *format != "binary_big_endian")
    return PlyError(path, "format '" + *format + "'");
  *skip_bytes = 0;
  *skip_lines = 0;
  for (PlyElement& e : elements) {
    FinishLayout(&e.layout);
    if (e.name == "vertex") {
      if (e.has_list) return PlyError(path, "the vertex element has a list property");
      *layout = e.layout;
      layout->num_points = e.count;
      layout->big_endian = *format == "binary_big_endian";
      *body_pos = pos;
      return Status::Ok();
    }
    if (e.has_list && *format != "ascii")
      return PlyError(path, "element '" + e.name + "' with a list property precedes vertex");
    *skip_bytes += e.count * static_cast<int64_t>(e.layout.record_bytes);
    *skip_lines += e.count;
  }
  return PlyError(path, "no vertex element");
}

// ---------------------------------------------------------------- decoding

double DecodeScalar(const char* p, ScalarKind kind, int size, bool big_endian) {
  unsigned char b[8];
  std::memcpy(b, p, size);
  if (big_endian) std::reverse(b, b + size);
  switch (kind) {
    case ScalarKind::kFloat: {
      if (size == 4) { float v; std::memcpy(&v, b, 4); return v; }
      double v; std::memcpy(&v, b, 8); return v;
    }
    case ScalarKind::kInt: {
      if (size == 1) { int8_t v; std::memcpy(&v, b, 1); return v; }
      if (size == 2) { int16_t v; std::memcpy(&v, b, 2); return v; }
      if (size == 4) { int32_t v; std::memcpy(&v, b, 4); return v; }
      int64_t v; std::memcpy(&v, b, 8); return static_cast<double>(v);
    }
    case ScalarKind::kUint: {
      if (size == 1) { uint8_t v; std::memcpy(&v, b, 1); return v; }
      if (size == 2) { uint16_t v; std::memcpy(&v, b, 2); return v; }
      if (size == 4) { uint32_t v; std::memcpy(&v, b, 4); return v; }
      uint64_t v; std::memcpy(&v, b, 8); return static_cast<double>(v);
    }
  }
  return 0.0;
}


Status PlanFields(const std::string& path, const FileLayout& layout, bool keep_fields,
                  FieldPlan* plan) {
  for (size_t i = 0; i < layout.fields.size(); ++i) {
    const FieldLayout& f = layout.fields[i];
    const int index = static_cast<int>(i);
    if (f.name == "x") plan->x = index;
    else if (f.name == "y") plan->y = index;
    else if (f.name == "z") plan->z = index;
    else if (keep_fields && f.count == 1 && f.name != "_") plan->kept.push_back(index);
  }
  if (plan->x < 0 || plan->y < 0 || plan->z < 0)
    return Status::InvalidInput(path + ": no x, y and z fields");
  for (int axis : {plan->x, plan->y, plan->z})
    if (layout.fields[axis].count != 1)
      return Status::InvalidInput(path + ": field " + layout.fields[axis].name + " has COUNT > 1");
  return Status::Ok();
}

void PrepareCloud(const FileLayout& layout, const FieldPlan& plan, PointCloudFile* cloud) {
  const size_t n = static_cast<size_t>(layout.num_points);
  ReserveWithHugePages(&cloud->points, n);
  cloud->points.resize(n);
  for (int f : plan.kept) {
    cloud->fields.push_back(PointCloudField{layout.fields[f].name, {}});
    ReserveWithHugePages(&cloud->fields.back().values, n);
    cloud->fields.back().values.resize(n);
  }
}

Status DecodeBinary(const std::string& path, const char* data, size_t size, const FileLayout& layout,
                    const FieldPlan& plan, PointCloudFile* cloud) {
  const uint64_t n = static_cast<uint64_t>(layout.num_points);
  if (layout.record_bytes == 0 || size / layout.record_bytes < n)
    return Status::InvalidInput(
        path + ": truncated: the header declares " + std::to_string(n) + " points, the data holds " +
        std::to_string(layout.record_bytes == 0 ? 0 : size / layout.record_bytes));
  PrepareCloud(layout, plan, cloud);
  for (int axis : {plan.x, plan.y, plan.z})
    cloud->xyz_single_precision |=
        layout.fields[axis].kind == ScalarKind::kFloat && layout.fields[axis].size == 4;
  const auto scalar = [&](const char* record, int f) {
    const FieldLayout& fl = layout.fields[f];
    return DecodeScalar(record + fl.offset, fl.kind, fl.size, layout.big_endian);
  };
  for (uint64_t i = 0; i < n; ++i) {
    const char* record = data + i * layout.record_bytes;
    cloud->points[i] = Eigen::Vector3d(scalar(record, plan.x), scalar(record, plan.y),
                                       scalar(record, plan.z));
    for (size_t k = 0; k < plan.kept.size(); ++k)
      cloud->fields[k].values[i] = static_cast<float>(scalar(record, plan.kept[k]));
  }
  return Status::Ok();
}

// Whitespace-separated numbers; newlines counted for messages. Skips
// `skip_lines` lines first (PLY elements before the vertices).
Status DecodeAscii(const std::string& path, const char* data, size_t size, int64_t skip_lines,
                   const FileLayout& layout, const FieldPlan& plan, PointCloudFile* cloud) {
  const char* p = data;
  const char* const end = data + size;
  for (int64_t s = 0; s < skip_lines; ++s) {
    p = static_cast<const char*>(std::memchr(p, '\n', end - p));
    if (p == nullptr) return Status::InvalidInput(path + ": truncated before the vertices");
    ++p;
  }
  const uint64_t n = static_cast<uint64_t>(layout.num_points);
  // Every number takes at least two bytes (a digit and a separator): a header
  // that declares more cannot be honest, and nothing is allocated for it.
  const uint64_t at_most = (static_cast<uint64_t>(end - p) + 1) / (2 * layout.record_scalars);
  if (n > at_most)
    return Status::InvalidInput(path + ": truncated: the header declares " + std::to_string(n) +
                                " points, the data can hold at most " + std::to_string(at_most));
  PrepareCloud(layout, plan, cloud);
  std::vector<double> record(layout.record_scalars);
  std::string token;
  for (uint64_t i = 0; i < n; ++i) {
    for (double& value : record) {
      while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
      const char* start = p;
      while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (start == p)
        return Status::InvalidInput(path + ": truncated: the header declares " +
                                    std::to_string(n) + " points, the data holds " +
                                    std::to_string(i));
      token.assign(start, p);
      char* parsed_end = nullptr;
      value = std::strtod(token.c_str(), &parsed_end);
      if (parsed_end == token.c_str() || *parsed_end != '\0') {
        if (p == end)  // the file ends inside this number
          return Status::InvalidInput(path + ": truncated: the header declares " +
                                      std::to_string(n) + " points, the data ends in point " +
                                      std::to_string(i));
        return Status::InvalidInput(path + ": point " + std::to_string(i) + ": '" +
                                    token.substr(0, 20) + "' is not a number");
      }
    }
    cloud->points[i] = Eigen::Vector3d(record[layout.fields[plan.x].first_scalar],
                                       record[layout.fields[plan.y].first_scalar],
                                       record[layout.fields[plan.z].first_scalar]);
    for (size_t k = 0; k < plan.kept.size(); ++k)
      cloud->fields[k].values[i] =
          static_cast<float>(record[layout.fields[plan.kept[k]].first_scalar]);
  }
  return Status::Ok();
}

Status ReadWholeFile(const std::string& path, std::string* text) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Status::InvalidInput(path + ": is a directory, not a point cloud file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::InvalidInput(path + ": cannot open (" + std::strerror(errno) + ")");
  // A regular file is read in one call into a buffer of its size (a stream
  // grown by doubling and copied out costs about three copies of the file:
  // a third of loading a 10 M point map); anything else (a pipe) is streamed.
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size >= 0 && in) {
    ReserveWithHugePages(text, static_cast<size_t>(size));
    text->resize(static_cast<size_t>(size));
    in.read(text->data(), size);
    if (in.gcount() != size) return Status::InvalidInput(path + ": read error (changed while read?)");
    return Status::Ok();
  }
  in.clear();
  in.seekg(0, std::ios::beg);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return Status::InvalidInput(path + ": read error");
  *text = std::move(buffer).str();
  return Status::Ok();
}

Status CheckPoints(const std::string& path, const PointCloudFile& cloud, bool allow_empty) {
  if (cloud.points.empty() && !allow_empty)
    return Status::InvalidInput(path + ": empty point cloud (0 points)");
  size_t bad = 0;
  for (const Eigen::Vector3d& p : cloud.points) bad += p.allFinite() ? 0 : 1;
  if (bad > 0)
    return Status::InvalidInput(path + ": " + std::to_string(bad) + " of " +
                                std::to_string(cloud.points.size()) +
                                " points have a non-finite coordinate (NaN or inf)");
  return Status::Ok();
}

StatusOr<PointCloudFile> ReadPcd(const std::string& path, const std::string& text,
                                 const PointCloudReadOptions& options) {
  FileLayout layout;
  std::string kind;
  size_t body_pos = 0;
  if (Status s = ParsePcdHeader(path, text, &layout, &kind, &body_pos); !s.ok()) return s;
  FieldPlan plan;
  if (Status s = PlanFields(path, layout, options.keep_fields, &plan); !s.ok()) return s;
  PointCloudFile cloud;
  cloud.format = "pcd " + kind;
  const Body body{text.data() + body_pos, text.size() - body_pos};
  Status s;
  if (kind == "ascii") {
    s = DecodeAscii(path, body.data, body.size, 0, layout, plan, &cloud);
  } else if (kind == "binary") {
    s = DecodeBinary(path, body.data, body.size, layout, plan, &cloud);
  } else {
    std::string records;
    s = DecompressPcd(path, body, layout, &records);
    if (s.ok()) s = DecodeBinary(path, records.data(), records.size(), layout, plan, &cloud);
  }
  if (!s.ok()) return s;
  return cloud;
}

StatusOr<PointCloudFile> ReadPly(const std::string& path, const std::string& text,
                                 const PointCloudReadOptions& options) {
  FileLayout layout;
  std::string format;
  int64_t skip_bytes = 0, skip_lines = 0;
  size_t body_pos = 0;
  if (Status s = ParsePlyHeader(path, text, &layout, &format, &skip_bytes, &skip_lines, &body_pos);
      !s.ok())
    return s;
  FieldPlan plan;
  if (Status s = PlanFields(path, layout, options.keep_fields, &plan); !s.ok()) return s;
  PointCloudFile cloud;
  cloud.format = "ply " + format;
  const char* body = text.data() + body_pos;
  const size_t size = text.size() - body_pos;
  Status s;
  if (format == "ascii") {
    s = DecodeAscii(path, body, size, skip_lines, layout, plan, &cloud);
  } else if (static_cast<uint64_t>(skip_bytes) > size) {
    s = Status::InvalidInput(path + ": truncated before the vertices");
  } else {
    s = DecodeBinary(path, body + skip_bytes, size - skip_bytes, layout, plan, &cloud);
  }
  if (!s.ok()) return s;
  return cloud;
}

}  // namespace

StatusOr<PointCloudFile> ReadPointCloud(const std::string& path,
                                        const PointCloudReadOptions& options) {
  std::string text;
  if (Status s = ReadWholeFile(path, &text); !s.ok()) return s;
  if (text.empty()) return Status::InvalidInput(path + ": empty file (0 bytes)");
  StatusOr<PointCloudFile> cloud = Status::InvalidInput(path + ": not a PCD or PLY point cloud");
  const auto starts_with = [&](const char* prefix) { return text.rfind(prefix, 0) == 0; };
  if (starts_with("ply\n") || starts_with("ply\r\n"))
    cloud = ReadPly(path, text, options);
  else if (starts_with("#") || starts_with("VERSION") || starts_with("FIELDS"))
    cloud = ReadPcd(path, text, options);
  if (!cloud.ok()) return cloud;
  if (Status s = CheckPoints(path, *cloud, options.allow_empty); !s.ok()) return s;
  return cloud;
}

// ------------------------------------------------------------ streaming PCD

namespace {

constexpr size_t kStreamBlockBytes = 1 << 20;       // bytes per read of the body
constexpr size_t kMaxPcdHeaderBytes = 16u << 20;    // a header past this has no DATA line

// True when `head` holds a complete DATA line (the header's last).
bool HasDataLine(const std::string& head) {
  for (size_t line = 0; line < head.size();) {
    const size_t end = head.find('\n', line);
    if (end == std::string::npos) return false;
    if (head.compare(line, 4, "DATA") == 0) return true;
    line = end + 1;
  }
  return false;
}

}  // namespace

struct PointCloudStream::Impl {
  std::string path;
  std::ifstream in;
  FileLayout layout;
  FieldPlan plan;
  std::string format;
  std::vector<PointCloudStreamField> fields;
  bool ascii = false;
  int64_t read = 0;     // points returned so far
  std::string buffer;   // body bytes read but not yet decoded, from pos on
  size_t pos = 0;
  bool eof = false;

  // Reads the next block into buffer (keeping the bytes from pos on). False
  // when the file has no more bytes.
  bool Refill() {
    if (eof) return false;
    buffer.erase(0, pos);
    pos = 0;
    const size_t old = buffer.size();
    buffer.resize(old + kStreamBlockBytes);
    in.read(&buffer[old], static_cast<std::streamsize>(kStreamBlockBytes));
    const size_t got = static_cast<size_t>(in.gcount());
    buffer.resize(old + got);
    if (got < kStreamBlockBytes) eof = true;
    return got > 0;
  }

  Status Truncated(int64_t holds) const {
    return Status::InvalidInput(path + ": truncated: the header declares " +
                                std::to_string(layout.num_points) + " points, the data holds " +
                                std::to_string(holds));
  }

  // The next whitespace-separated word of an ascii body; false at the end.
  bool NextWord(std::string* word) {
    word->clear();
    for (;;) {
      while (pos < buffer.size() && std::isspace(static_cast<unsigned char>(buffer[pos]))) ++pos;
      if (pos < buffer.size()) break;
      if (!Refill()) return false;
    }
    for (;;) {
      const size_t start = pos;
      while (pos < buffer.size() && !std::isspace(static_cast<unsigned char>(buffer[pos]))) ++pos;
      word->append(buffer, start, pos - start);
      if (pos < buffer.size() || !Refill()) return true;
    }
  }

  Status ReadAsciiPoint(std::vector<double>* record) {
    std::string word;
    for (double& value : *record) {
      if (!NextWord(&word)) return Truncated(read);
      char* end = nullptr;
      value = std::strtod(word.c_str(), &end);
      if (end == word.c_str() || *end != '\0') {
        if (pos >= buffer.size() && eof)
          return Status::InvalidInput(path + ": truncated: the header declares " +
                                      std::to_string(layout.num_points) +
                                      " points, the data ends in point " + std::to_string(read));
        return Status::InvalidInput(path + ": point " + std::to_string(read) + ": '" +
                                    word.substr(0, 20) + "' is not a number");
      }
    }
    return Status::Ok();
  }

  // One binary record at buffer[pos]; the caller made sure it is there.
  void DecodeRecord(std::vector<double>* record) {
    const char* p = buffer.data() + pos;
    for (size_t f = 0; f < layout.fields.size(); ++f) {
      const FieldLayout& fl = layout.fields[f];
      (*record)[fl.first_scalar] = fl.count == 1 ? DecodeScalar(p + fl.offset, fl.kind, fl.size, false) : 0.0;
    }
    pos += layout.record_bytes;
  }

  Status NextPoint(std::vector<double>* record) {
    if (ascii) return ReadAsciiPoint(record);
    if (buffer.size() - pos < layout.record_bytes) {
      while (buffer.size() - pos < layout.record_bytes)
        if (!Refill()) return Truncated(read);
    }
    DecodeRecord(record);
    return Status::Ok();
  }
};

PointCloudStream::PointCloudStream() : impl_(std::make_unique<Impl>()) {}
PointCloudStream::~PointCloudStream() = default;

const std::vector<PointCloudStreamField>& PointCloudStream::fields() const { return impl_->fields; }
int64_t PointCloudStream::size() const { return impl_->layout.num_points; }
const std::string& PointCloudStream::format() const { return impl_->format; }

Status PointCloudStream::Open(const std::string& path) {
  impl_ = std::make_unique<Impl>();
  Impl& m = *impl_;
  m.path = path;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    return Status::InvalidInput(path + ": is a directory, not a point cloud file");
  m.in.open(path, std::ios::binary);
  if (!m.in) return Status::InvalidInput(path + ": cannot open (" + std::strerror(errno) + ")");
  while (!HasDataLine(m.buffer) && m.buffer.size() < kMaxPcdHeaderBytes && m.Refill()) {
  }
  const std::string& head = m.buffer;
  if (head.empty()) return Status::InvalidInput(path + ": empty file (0 bytes)");
  if (head.rfind("ply", 0) == 0)
    return Status::InvalidInput(path + ": a PLY file; streaming reads PCD only (DATA ascii or "
                                       "binary, as rvlio writes map.pcd)");
  if (!(head.rfind("#", 0) == 0 || head.rfind("VERSION", 0) == 0 || head.rfind("FIELDS", 0) == 0))
    return Status::InvalidInput(path + ": not a PCD point cloud");
  std::string kind;
  size_t body_pos = 0;
  if (Status s = ParsePcdHeader(path, head, &m.layout, &kind, &body_pos); !s.ok()) return s;
  if (kind == "binary_compressed")
    return Status::InvalidInput(path + ": DATA binary_compressed cannot be streamed (its fields "
                                       "are stored one after another); convert it to binary "
                                       "first, e.g. pcl_convert_pcd_ascii_binary IN OUT 1");
  if (Status s = PlanFields(path, m.layout, true, &m.plan); !s.ok()) return s;
  m.ascii = kind == "ascii";
  m.format = "pcd " + kind;
  m.pos = body_pos;
  for (int f : m.plan.kept) {
    const FieldLayout& fl = m.layout.fields[f];
    m.fields.push_back({fl.name, fl.kind == ScalarKind::kFloat ? 'F' : fl.kind == ScalarKind::kInt ? 'I' : 'U', fl.size});
  }
  return Status::Ok();
}

StatusOr<size_t> PointCloudStream::Read(size_t max_points, PointCloudChunk* chunk) {
  Impl& m = *impl_;
  const size_t n = static_cast<size_t>(
      std::min<int64_t>(static_cast<int64_t>(max_points), m.layout.num_points - m.read));
  chunk->points.resize(n);
  chunk->fields.resize(m.plan.kept.size());
  for (std::vector<double>& f : chunk->fields) f.resize(n);
  std::vector<double> record(m.layout.record_scalars);
  const auto at = [&](int f) { return record[m.layout.fields[f].first_scalar]; };
  for (size_t i = 0; i < n; ++i) {
    if (Status s = m.NextPoint(&record); !s.ok()) return s;
    const Eigen::Vector3d p(at(m.plan.x), at(m.plan.y), at(m.plan.z));
    if (!p.allFinite())
      return Status::InvalidInput(m.path + ": point " + std::to_string(m.read) +
                                  " has a non-finite coordinate (NaN or inf)");
    chunk->points[i] = p;
    for (size_t k = 0; k < m.plan.kept.size(); ++k) chunk->fields[k][i] = at(m.plan.kept[k]);
    ++m.read;
  }
  return n;
}

}  // namespace rvlio
