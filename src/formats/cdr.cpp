#include "rvlio/formats/cdr.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace rvlio::cdr {
namespace {

constexpr size_t kEncapsulationSize = 4;
// Smallest CDR size of a sensor_msgs/PointField (empty name: length + NUL,
// aligned offset, datatype, aligned count).
constexpr size_t kMinPointFieldSize = 4 + 1 + 3 + 4 + 1 + 3 + 4;
// livox_ros_driver2/CustomPoint: uint32 + 3 float32 + 3 uint8, padded to 4.
constexpr size_t kMinLivoxPointSize = 19;

bool HostIsBigEndian() {
  const uint16_t one = 1;
  uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 0;
}

const char kSeparator[] =
    "\n================================================================================\n";

const char kHeaderDef[] =
    "MSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id";
const char kTimeDef[] =
    "MSG: builtin_interfaces/Time\n"
    "int32 sec\n"
    "uint32 nanosec";

std::string WithDependencies(const std::string& main, const std::vector<const char*>& deps) {
  std::string out = main;
  for (const char* d : deps) out += std::string(kSeparator) + d;
  return out;
}

std::string Where(const std::string& type, const std::string& topic) {
  return type + (topic.empty() ? std::string() : " on " + topic);
}

}  // namespace

const std::string& PointCloud2Definition() {
  static const std::string def = WithDependencies(
      "std_msgs/Header header\n"
      "uint32 height\n"
      "uint32 width\n"
      "PointField[] fields\n"
      "bool is_bigendian\n"
      "uint32 point_step\n"
      "uint32 row_step\n"
      "uint8[] data\n"
      "bool is_dense",
      {kHeaderDef, kTimeDef,
       "MSG: sensor_msgs/PointField\n"
       "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\n"
       "uint8 INT32 = 5\nuint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
       "string name\n"
       "uint32 offset\n"
       "uint8 datatype\n"
       "uint32 count"});
  return def;
}

const std::string& ImuDefinition() {
  static const std::string def = WithDependencies(
      "std_msgs/Header header\n"
      "geometry_msgs/Quaternion orientation\n"
      "float64[9] orientation_covariance\n"
      "geometry_msgs/Vector3 angular_velocity\n"
      "float64[9] angular_velocity_covariance\n"
      "geometry_msgs/Vector3 linear_acceleration\n"
      "float64[9] linear_acceleration_covariance",
      {kHeaderDef, kTimeDef,
       "MSG: geometry_msgs/Quaternion\n"
       "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
       "MSG: geometry_msgs/Vector3\n"
       "float64 x\nfloat64 y\nfloat64 z"});
  return def;
}

const std::string& NavSatFixDefinition() {
  static const std::string def = WithDependencies(
      "std_msgs/Header header\n"
      "NavSatStatus status\n"
      "float64 latitude\n"
      "float64 longitude\n"
      "float64 altitude\n"
      "float64[9] position_covariance\n"
      "uint8 position_covariance_type",
      {kHeaderDef, kTimeDef, "MSG: sensor_msgs/NavSatStatus\nint8 status\nuint16 service"});
  return def;
}

const std::string& LivoxCustomMsgDefinition() {
  static const std::string def = WithDependencies(
      "std_msgs/Header header\n"
      "uint64 timebase\n"
      "uint32 point_num\n"
      "uint8 lidar_id\n"
      "uint8[3] rsvd\n"
      "CustomPoint[] points",
      {kHeaderDef, kTimeDef,
       "MSG: livox_ros_driver2/CustomPoint\n"
       "uint32 offset_time\n"
       "float32 x\nfloat32 y\nfloat32 z\n"
       "uint8 reflectivity\n"
       "uint8 tag\n"
       "uint8 line"});
  return def;
}

// ---------------------------------------------------------------------------
// Reader

Reader::Reader(const uint8_t* data, size_t size, std::string what)
    : data_(data), size_(data == nullptr ? 0 : size), what_(std::move(what)) {}

Status Reader::Error(const char* field, const std::string& problem) const {
  return Status::InvalidInput("CDR " + what_ + ": field '" + field + "' at byte " +
                              std::to_string(pos_) + ": " + problem);
}

Status Reader::Begin() {
  if (size_ < kEncapsulationSize)
    return Error("encapsulation", "payload of " + std::to_string(size_) +
                                      " bytes is shorter than the 4-byte CDR header");
  if (data_[0] != 0x00 || data_[1] > 0x01) {
    char id[16];
    std::snprintf(id, sizeof(id), "0x%02x%02x", data_[0], data_[1]);
    return Error("encapsulation", std::string("unsupported representation ") + id +
                                      " (only plain CDR, big or little endian)");
  }
  const bool little = data_[1] == 0x01;
  swap_ = little == HostIsBigEndian();
  pos_ = kEncapsulationSize;
  origin_ = kEncapsulationSize;
  return Status::Ok();
}

Status Reader::Align(size_t n, const char* field) {
  const size_t rel = pos_ - origin_;
  const size_t pad = (n - rel % n) % n;
  if (pad > size_ - pos_) return Error(field, "payload ends inside alignment padding");
  pos_ += pad;
  return Status::Ok();
}

Status Reader::Raw(void* out, size_t n, const char* field) {
  if (n > size_ - pos_)
    return Error(field, "needs " + std::to_string(n) + " bytes, " +
                            std::to_string(size_ - pos_) + " left");
  std::memcpy(out, data_ + pos_, n);
  if (swap_) std::reverse(static_cast<uint8_t*>(out), static_cast<uint8_t*>(out) + n);
  pos_ += n;
  return Status::Ok();
}

#define RVLIO_CDR_READ(Name, Type)                          \
  Status Reader::Name(Type* v, const char* field) {         \
    if (Status s = Align(sizeof(Type), field); !s.ok()) return s; \
    return Raw(v, sizeof(Type), field);                     \
  }
RVLIO_CDR_READ(U8, uint8_t)
RVLIO_CDR_READ(U16, uint16_t)
RVLIO_CDR_READ(U32, uint32_t)
RVLIO_CDR_READ(I32, int32_t)
RVLIO_CDR_READ(U64, uint64_t)
RVLIO_CDR_READ(F32, float)
RVLIO_CDR_READ(F64, double)
#undef RVLIO_CDR_READ

Status Reader::Bool(bool* v, const char* field) {
  uint8_t b = 0;
  if (Status s = U8(&b, field); !s.ok()) return s;
  if (b > 1) return Error(field, "boolean byte " + std::to_string(b) + " is neither 0 nor 1");
  *v = b == 1;
  return Status::Ok();
}

Status Reader::String(std::string* v, const char* field) {
  uint32_t length = 0;
  if (Status s = U32(&length, field); !s.ok()) return s;
  if (length > size_ - pos_)
    return Error(field, "string length " + std::to_string(length) + " exceeds the " +
                            std::to_string(size_ - pos_) + " bytes left");
  if (length == 0) {  // not written by Fast-CDR, but harmless
    v->clear();
    return Status::Ok();
  }
  if (data_[pos_ + length - 1] != '\0') return Error(field, "string is not NUL-terminated");
  v->assign(reinterpret_cast<const char*>(data_ + pos_), length - 1);
  pos_ += length;
  return Status::Ok();
}

Status Reader::SequenceCount(uint32_t* count, size_t min_element_size, const char* field) {
  if (Status s = U32(count, field); !s.ok()) return s;
  const size_t left = size_ - pos_;
  if (min_element_size > 0 && *count > left / min_element_size)
    return Error(field, "sequence length " + std::to_string(*count) + " exceeds the " +
                            std::to_string(left) + " bytes left");
  return Status::Ok();
}

Status Reader::ByteSequence(const uint8_t** bytes, size_t* size, const char* field) {
  uint32_t count = 0;
  if (Status s = SequenceCount(&count, 1, field); !s.ok()) return s;
  *bytes = data_ + pos_;
  *size = count;
  pos_ += count;
  return Status::Ok();
}

Status Reader::Header(TimeNs* stamp_ns, std::string* frame_id) {
  int32_t sec = 0;
  uint32_t nanosec = 0;
  if (Status s = I32(&sec, "header.stamp.sec"); !s.ok()) return s;
  if (Status s = U32(&nanosec, "header.stamp.nanosec"); !s.ok()) return s;
  if (nanosec >= 1000000000u)
    return Error("header.stamp.nanosec", std::to_string(nanosec) + " is not below 1e9");
  *stamp_ns = static_cast<TimeNs>(sec) * kNsPerSecond + static_cast<TimeNs>(nanosec);
  return String(frame_id, "header.frame_id");
}

// ---------------------------------------------------------------------------
// Writer

Writer::Writer() { buffer_ = {0x00, 0x01, 0x00, 0x00}; }

void Writer::Align(size_t n) {
  const size_t rel = buffer_.size() - kEncapsulationSize;
  buffer_.resize(buffer_.size() + (n - rel % n) % n, 0);
}

void Writer::Raw(const void* data, size_t n) {
  const size_t at = buffer_.size();
  buffer_.resize(at + n);
  std::memcpy(buffer_.data() + at, data, n);
  if (HostIsBigEndian()) std::reverse(buffer_.begin() + at, buffer_.end());
}

#define RVLIO_CDR_WRITE(Name, Type) \
  void Writer::Name(Type v) {       \
    Align(sizeof(Type));            \
    Raw(&v, sizeof(Type));          \
  }
RVLIO_CDR_WRITE(U8, uint8_t)
RVLIO_CDR_WRITE(U16, uint16_t)
RVLIO_CDR_WRITE(U32, uint32_t)
RVLIO_CDR_WRITE(I32, int32_t)
RVLIO_CDR_WRITE(U64, uint64_t)
RVLIO_CDR_WRITE(F32, float)
RVLIO_CDR_WRITE(F64, double)
#undef RVLIO_CDR_WRITE

void Writer::String(const std::string& v) {
  U32(static_cast<uint32_t>(v.size() + 1));
  buffer_.insert(buffer_.end(), v.begin(), v.end());
  buffer_.push_back(0);
}

void Writer::Bytes(const uint8_t* data, size_t size) {
  U32(static_cast<uint32_t>(size));
  buffer_.insert(buffer_.end(), data, data + size);
}

void Writer::Header(TimeNs stamp_ns, const std::string& frame_id) {
  // builtin_interfaces/Time: floor division, nanosec in [0, 1e9).
  TimeNs sec = stamp_ns / kNsPerSecond, nsec = stamp_ns % kNsPerSecond;
  if (nsec < 0) {
    nsec += kNsPerSecond;
    --sec;
  }
  I32(static_cast<int32_t>(sec));
  U32(static_cast<uint32_t>(nsec));
  String(frame_id);
}

// ---------------------------------------------------------------------------
// Messages

namespace {

Status ReadPointField(Reader* r, PointField* f) {
  if (Status s = r->String(&f->name, "fields.name"); !s.ok()) return s;
  if (Status s = r->U32(&f->offset, "fields.offset"); !s.ok()) return s;
  if (Status s = r->U8(&f->datatype, "fields.datatype"); !s.ok()) return s;
  return r->U32(&f->count, "fields.count");
}

template <size_t N>
Status ReadDoubles(Reader* r, std::array<double, N>* out, const char* field) {
  for (double& v : *out) {
    if (Status s = r->F64(&v, field); !s.ok()) return s;
  }
  return Status::Ok();
}

Status ReadLivoxPoint(Reader* r, LivoxCustomPoint* p) {
  if (Status s = r->U32(&p->offset_time, "points.offset_time"); !s.ok()) return s;
  if (Status s = r->F32(&p->x, "points.x"); !s.ok()) return s;
  if (Status s = r->F32(&p->y, "points.y"); !s.ok()) return s;
  if (Status s = r->F32(&p->z, "points.z"); !s.ok()) return s;
  if (Status s = r->U8(&p->reflectivity, "points.reflectivity"); !s.ok()) return s;
  if (Status s = r->U8(&p->tag, "points.tag"); !s.ok()) return s;
  return r->U8(&p->line, "points.line");
}

}  // namespace

StatusOr<PointCloud2View> DecodePointCloud2(const uint8_t* data, size_t size,
                                            const std::string& topic) {
  Reader r(data, size, Where(kPointCloud2Type, topic));
  PointCloud2View v;
  v.topic = topic;
  std::string frame_id;
  uint32_t field_count = 0;
  bool is_dense = false;
  Status s = r.Begin();
  if (s.ok()) s = r.Header(&v.header_stamp_ns, &frame_id);
  if (s.ok()) s = r.U32(&v.height, "height");
  if (s.ok()) s = r.U32(&v.width, "width");
  if (s.ok()) s = r.SequenceCount(&field_count, kMinPointFieldSize, "fields");
  if (s.ok()) v.fields.resize(field_count);
  for (uint32_t i = 0; s.ok() && i < field_count; ++i) s = ReadPointField(&r, &v.fields[i]);
  if (s.ok()) s = r.Bool(&v.is_bigendian, "is_bigendian");
  if (s.ok()) s = r.U32(&v.point_step, "point_step");
  if (s.ok()) s = r.U32(&v.row_step, "row_step");
  if (s.ok()) s = r.ByteSequence(&v.data, &v.data_size, "data");
  if (s.ok()) s = r.Bool(&is_dense, "is_dense");
  if (!s.ok()) return s;
  return v;
}

StatusOr<ImuMessage> DecodeImu(const uint8_t* data, size_t size, const std::string& topic) {
  Reader r(data, size, Where(kImuType, topic));
  ImuMessage m;
  Status s = r.Begin();
  if (s.ok()) s = r.Header(&m.header_stamp_ns, &m.frame_id);
  if (s.ok()) s = ReadDoubles(&r, &m.orientation_xyzw, "orientation");
  if (s.ok()) s = ReadDoubles(&r, &m.orientation_covariance, "orientation_covariance");
  if (s.ok()) s = ReadDoubles(&r, &m.angular_velocity, "angular_velocity");
  if (s.ok()) s = ReadDoubles(&r, &m.angular_velocity_covariance, "angular_velocity_covariance");
  if (s.ok()) s = ReadDoubles(&r, &m.linear_acceleration, "linear_acceleration");
  if (s.ok())
    s = ReadDoubles(&r, &m.linear_acceleration_covariance, "linear_acceleration_covariance");
  if (!s.ok()) return s;
  return m;
}

StatusOr<LivoxCustomMsg> DecodeLivoxCustomMsg(const uint8_t* data, size_t size,
                                              const std::string& topic) {
  Reader r(data, size, Where(kLivoxRos2Type, topic));
  LivoxCustomMsg m;
  uint32_t count = 0;
  Status s = r.Begin();
  if (s.ok()) s = r.Header(&m.header_stamp_ns, &m.frame_id);
  if (s.ok()) s = r.U64(&m.timebase, "timebase");
  if (s.ok()) s = r.U32(&m.point_num, "point_num");
  if (s.ok()) s = r.U8(&m.lidar_id, "lidar_id");
  for (uint8_t& b : m.rsvd) {
    if (s.ok()) s = r.U8(&b, "rsvd");
  }
  if (s.ok()) s = r.SequenceCount(&count, kMinLivoxPointSize, "points");
  if (s.ok()) m.points.resize(count);
  for (uint32_t i = 0; s.ok() && i < count; ++i) s = ReadLivoxPoint(&r, &m.points[i]);
  if (!s.ok()) return s;
  return m;
}

StatusOr<std::string> DecodeString(const uint8_t* data, size_t size, const std::string& topic) {
  Reader r(data, size, Where(kStringType, topic));
  std::string text;
  Status s = r.Begin();
  if (s.ok()) s = r.String(&text, "data");
  if (!s.ok()) return s;
  return text;
}

std::vector<uint8_t> EncodePointCloud2(const PointCloud2View& cloud, const std::string& frame_id,
                                       bool is_dense) {
  Writer w;
  w.Header(cloud.header_stamp_ns, frame_id);
  w.U32(cloud.height);
  w.U32(cloud.width);
  w.U32(static_cast<uint32_t>(cloud.fields.size()));
  for (const PointField& f : cloud.fields) {
    w.String(f.name);
    w.U32(f.offset);
    w.U8(f.datatype);
    w.U32(f.count);
  }
  w.Bool(cloud.is_bigendian);
  w.U32(cloud.point_step);
  w.U32(cloud.row_step);
  w.Bytes(cloud.data, cloud.data_size);
  w.Bool(is_dense);
  return w.Take();
}

std::vector<uint8_t> EncodeImu(const ImuMessage& m) {
  Writer w;
  w.Header(m.header_stamp_ns, m.frame_id);
  for (double v : m.orientation_xyzw) w.F64(v);
  for (double v : m.orientation_covariance) w.F64(v);
  for (double v : m.angular_velocity) w.F64(v);
  for (double v : m.angular_velocity_covariance) w.F64(v);
  for (double v : m.linear_acceleration) w.F64(v);
  for (double v : m.linear_acceleration_covariance) w.F64(v);
  return w.Take();
}

std::vector<uint8_t> EncodeLivoxCustomMsg(const LivoxCustomMsg& m) {
  Writer w;
  w.Header(m.header_stamp_ns, m.frame_id);
  w.U64(m.timebase);
  w.U32(m.point_num);
  w.U8(m.lidar_id);
  for (uint8_t b : m.rsvd) w.U8(b);
  w.U32(static_cast<uint32_t>(m.points.size()));
  for (const LivoxCustomPoint& p : m.points) {
    w.U32(p.offset_time);
    w.F32(p.x);
    w.F32(p.y);
    w.F32(p.z);
    w.U8(p.reflectivity);
    w.U8(p.tag);
    w.U8(p.line);
  }
  return w.Take();
}

std::vector<uint8_t> EncodeString(const std::string& text) {
  Writer w;
  w.String(text);
  return w.Take();
}


// ---------------------------------------------------------------------------
// What `rvlio live` publishes (nav_messages.h), field by field as in the
// public definitions of nav_msgs, geometry_msgs, tf2_msgs and diagnostic_msgs.
// ---------------------------------------------------------------------------

namespace {

void WritePose(Writer* w, const PoseMessage& p) {
  for (double v : p.position) w->F64(v);
  for (double v : p.orientation_xyzw) w->F64(v);
}

Status ReadPose(Reader* r, PoseMessage* p) {
  if (Status s = ReadDoubles(r, &p->position, "pose.position"); !s.ok()) return s;
  return ReadDoubles(r, &p->orientation_xyzw, "pose.orientation");
}

void WriteTransform(Writer* w, const TransformMessage& t) {
  w->Header(t.stamp_ns, t.frame_id);
  w->String(t.child_frame_id);
  for (double v : t.translation) w->F64(v);
  for (double v : t.rotation_xyzw) w->F64(v);
}

}  // namespace

std::vector<uint8_t> EncodeOdometry(const OdometryMessage& m) {
  Writer w;
  w.Header(m.stamp_ns, m.frame_id);
  w.String(m.child_frame_id);
  WritePose(&w, m.pose);
  for (double v : m.pose_covariance) w.F64(v);
  for (double v : m.linear_velocity) w.F64(v);
  for (double v : m.angular_velocity) w.F64(v);
  for (double v : m.twist_covariance) w.F64(v);
  return w.Take();
}

std::vector<uint8_t> EncodeTfMessage(const std::vector<TransformMessage>& transforms) {
  Writer w;
  w.U32(static_cast<uint32_t>(transforms.size()));
  for (const TransformMessage& t : transforms) WriteTransform(&w, t);
  return w.Take();
}

std::vector<uint8_t> EncodePath(const PathMessage& m) {
  Writer w;
  w.Header(m.stamp_ns, m.frame_id);
  w.U32(static_cast<uint32_t>(m.poses.size()));
  for (const auto& [t_ns, pose] : m.poses) {
    w.Header(t_ns, m.frame_id);
    WritePose(&w, pose);
  }
  return w.Take();
}

std::vector<uint8_t> EncodeDiagnosticArray(const DiagnosticMessage& m) {
  Writer w;
  w.Header(m.stamp_ns, "");
  w.U32(1);  // one DiagnosticStatus
  w.U8(m.level);
  w.String(m.name);
  w.String(m.message);
  w.String(m.hardware_id);
  w.U32(static_cast<uint32_t>(m.values.size()));
  for (const auto& [key, value] : m.values) {
    w.String(key);
    w.String(value);
  }
  return w.Take();
}

StatusOr<OdometryMessage> DecodeOdometry(const uint8_t* data, size_t size,
                                         const std::string& topic) {
  Reader r(data, size, Where(kOdometryType, topic));
  OdometryMessage m;
  Status s = r.Begin();
  if (s.ok()) s = r.Header(&m.stamp_ns, &m.frame_id);
  if (s.ok()) s = r.String(&m.child_frame_id, "child_frame_id");
  if (s.ok()) s = ReadPose(&r, &m.pose);
  if (s.ok()) s = ReadDoubles(&r, &m.pose_covariance, "pose.covariance");
  if (s.ok()) s = ReadDoubles(&r, &m.linear_velocity, "twist.linear");
  if (s.ok()) s = ReadDoubles(&r, &m.angular_velocity, "twist.angular");
  if (s.ok()) s = ReadDoubles(&r, &m.twist_covariance, "twist.covariance");
  if (!s.ok()) return s;
  return m;
}

StatusOr<std::vector<TransformMessage>> DecodeTfMessage(const uint8_t* data, size_t size,
                                                        const std::string& topic) {
  Reader r(data, size, Where(kTfMessageType, topic));
  uint32_t count = 0;
  Status s = r.Begin();
  // The smallest TransformStamped: stamp, empty frame and child, 7 doubles.
  if (s.ok()) s = r.SequenceCount(&count, 8 + 5 + 5 + 7 * 8, "transforms");
  std::vector<TransformMessage> out(s.ok() ? count : 0);
  for (TransformMessage& t : out) {
    if (s.ok()) s = r.Header(&t.stamp_ns, &t.frame_id);
    if (s.ok()) s = r.String(&t.child_frame_id, "child_frame_id");
    if (s.ok()) s = ReadDoubles(&r, &t.translation, "transform.translation");
    if (s.ok()) s = ReadDoubles(&r, &t.rotation_xyzw, "transform.rotation");
  }
  if (!s.ok()) return s;
  return out;
}

}  // namespace rvlio::cdr
