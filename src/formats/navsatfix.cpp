// NavSatFix messages (formats/navsatfix.h): parsed from their ROS1 and CDR
// bytes without the ROS message classes, and read from any recording kind.
#include "rvlio/formats/navsatfix.h"

#include <cmath>
#include <exception>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "ros1_wire.h"
#include "rosbag_common.h"
#include "sensor_reader_common.h"
#include "rvlio/common/text.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/recording.h"

namespace rvlio {
namespace {

Status Short(const std::string& where) {
  return Status::InvalidInput(where + ": a NavSatFix message is too short (truncated or corrupt)");
}

// An accepted fix goes to *out; one without a solution is counted. The
// position's range is the message's promise: out of it, the topic holds
// something else (or garbage), so it is refused.
Status Accept(const NavSatFix& fix, const std::string& where, NavSatFixStats* stats,
              std::vector<NavSatFix>* out) {
  const int64_t index = stats->messages++;
  if (fix.status <= kNavSatStatusNoFix || !std::isfinite(fix.latitude_deg) ||
      !std::isfinite(fix.longitude_deg) || !std::isfinite(fix.altitude_m)) {
    ++stats->no_fix;
    return Status::Ok();
  }
  if (std::abs(fix.latitude_deg) > 90.0 || std::abs(fix.longitude_deg) > 180.0)
    return Status::InvalidInput(where + ": message " + std::to_string(index) + " (stamp " +
                                FormatFixed(NsToSeconds(fix.header_stamp_ns), 3) +
                                " s) has latitude " + FormatG(fix.latitude_deg) + ", longitude " +
                                FormatG(fix.longitude_deg) +
                                " (degrees: latitude within [-90, 90], longitude within "
                                "[-180, 180])");
  out->push_back(fix);
  return Status::Ok();
}

Status ReadRos1(const std::string& path, const std::string& topic, const std::string& where,
                NavSatFixStats* stats, std::vector<NavSatFix>* out) {
  rosbag::Bag bag;
  if (Status s = bag_detail::OpenForRead(path, &bag); !s.ok()) return s;
  try {
    if (Status s = bag_detail::RequireTopic(path, bag_detail::TopicTypes(bag), topic,
                                            kNavSatFixRos1Type, "gnss.topic");
        !s.ok())
      return s;
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    std::vector<uint8_t> bytes;
    for (const rosbag::MessageInstance& m : view) {
      const size_t size = bag_detail::ReadRawMessage(m, &bytes);
      StatusOr<NavSatFix> fix = ParseRos1NavSatFix(bytes.data(), size, where);
      if (!fix.ok()) return fix.status();
      if (Status s = Accept(*fix, where, stats, out); !s.ok()) return s;
    }
  } catch (const std::exception& e) {
    return Status::InvalidInput("reading bag '" + path + "' failed (" + e.what() + ")");
  }
  return Status::Ok();
}

Status ReadRos2(const std::string& path, const std::string& topic, const std::string& where,
                NavSatFixStats* stats, std::vector<NavSatFix>* out) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  if (!source.ok()) return source.status();
  std::map<std::string, std::string> types;
  int index = -1;
  for (size_t i = 0; i < (*source)->topics().size(); ++i) {
    const RecordingTopic& t = (*source)->topics()[i];
    types[t.name] = t.type;
    if (t.name == topic) index = static_cast<int>(i);
  }
  if (Status s = bag_detail::RequireTopic(path, types, topic, kNavSatFixRos2Type, "gnss.topic");
      !s.ok())
    return s;
  if (Status s = (*source)->SetTopicFilter({index}); !s.ok()) return s;
  RawMessage m;
  while (true) {
    StatusOr<bool> more = (*source)->Next(&m);
    if (!more.ok()) return more.status();
    if (!*more) return Status::Ok();
    StatusOr<NavSatFix> fix = DecodeNavSatFixCdr(m.data.data(), m.data.size(), where);
    if (!fix.ok()) return fix.status();
    if (Status s = Accept(*fix, where, stats, out); !s.ok()) return s;
  }
}

}  // namespace

StatusOr<NavSatFix> ParseRos1NavSatFix(const uint8_t* data, size_t size,
                                       const std::string& where) {
  bag_detail::Ros1WireReader r(data, size);
  NavSatFix f;
  if (!r.ReadHeader(&f.header_stamp_ns, &f.frame_id) || !r.Read(&f.status) ||
      !r.Read(&f.service) || !r.Read(&f.latitude_deg) || !r.Read(&f.longitude_deg) ||
      !r.Read(&f.altitude_m))
    return Short(where);
  for (double& c : f.position_covariance)
    if (!r.Read(&c)) return Short(where);
  if (!r.Read(&f.covariance_type)) return Short(where);
  return f;
}

StatusOr<NavSatFix> DecodeNavSatFixCdr(const uint8_t* data, size_t size,
                                       const std::string& where) {
  cdr::Reader r(data, size, where);
  NavSatFix f;
  uint8_t status = 0;
  Status s = r.Begin();
  if (s.ok()) s = r.Header(&f.header_stamp_ns, &f.frame_id);
  if (s.ok()) s = r.U8(&status, "status.status");
  if (s.ok()) s = r.U16(&f.service, "status.service");
  if (s.ok()) s = r.F64(&f.latitude_deg, "latitude");
  if (s.ok()) s = r.F64(&f.longitude_deg, "longitude");
  if (s.ok()) s = r.F64(&f.altitude_m, "altitude");
  for (double& c : f.position_covariance)
    if (s.ok()) s = r.F64(&c, "position_covariance");
  if (s.ok()) s = r.U8(&f.covariance_type, "position_covariance_type");
  if (!s.ok()) return s;
  f.status = static_cast<int8_t>(status);
  return f;
}

std::vector<uint8_t> EncodeNavSatFixCdr(const NavSatFix& f) {
  cdr::Writer w;
  w.Header(f.header_stamp_ns, f.frame_id);
  w.U8(static_cast<uint8_t>(f.status));
  w.U16(f.service);
  w.F64(f.latitude_deg);
  w.F64(f.longitude_deg);
  w.F64(f.altitude_m);
  for (double c : f.position_covariance) w.F64(c);
  w.U8(f.covariance_type);
  return w.Take();
}

StatusOr<std::vector<NavSatFix>> ReadNavSatFixes(const std::string& path, const std::string& topic,
                                                 NavSatFixStats* stats) {
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  const std::string where = "gnss.topic '" + topic + "' in '" + path + "'";
  std::vector<NavSatFix> out;
  *stats = {};
  Status s;
  if (*kind == RecordingKind::kRos1Bag) s = ReadRos1(path, topic, where, stats, &out);
  else if (*kind == RecordingKind::kPcap)
    s = Status::InvalidInput(where + ": a pcap capture holds no NavSatFix messages");
  else s = ReadRos2(path, topic, where, stats, &out);
  if (!s.ok()) return s;
  return out;
}

}  // namespace rvlio
