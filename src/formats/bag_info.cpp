// ReadBagInfo: what `rvlio info` prints about a recording (ROS1 bag through
// rosbag_storage; ROS 2 .db3 / .mcap / bag folder through formats/recording).
#include <algorithm>
#include <cstring>
#include <exception>
#include <fstream>
#include <functional>
#include <limits>
#include <map>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "ros1_raw_message.h"
#include "ouster_source.h"
#include "rvlio/formats/pcap.h"
#include "ros1_messages.h"
#include "rosbag_common.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/recording.h"
#include "rvlio/formats/sensor_bag.h"

namespace rvlio {
namespace {

constexpr int kScansToSample = 5;

// Accumulates layout, fields and mean point count over the first few clouds.
class CloudSampler {
 public:
  explicit CloudSampler(BagTopicInfo* info) : info_(info) {
    lidar_.min_range = 0.0;  // auto layout and stamp; no range crop: count every valid point
    lidar_.max_range = std::numeric_limits<double>::max();
  }
  bool Full() const { return done_ || info_->scans_sampled >= kScansToSample; }

  // A cloud or why it could not be deserialized.
  void Add(const StatusOr<PointCloud2View>& cloud) {
    if (!cloud.ok()) return Fail(cloud.status().message());
    if (info_->fields.empty()) {
      for (const auto& f : cloud->fields) info_->fields.push_back(f.name);
    }
    DecodeStats stats;
    Record(DecodePointCloud2(*cloud, lidar_, &stats), stats);
  }

  // A Livox CustomMsg (ROS1 or ROS 2) or why it could not be deserialized.
  void Add(const StatusOr<LivoxCustomMsg>& msg) {
    if (!msg.ok()) return Fail(msg.status().message());
    if (info_->fields.empty())
      info_->fields = {"offset_time", "x", "y", "z", "reflectivity", "tag", "line"};
    DecodeStats stats;
    Record(DecodeLivoxCustomMsg(*msg, lidar_, &stats), stats);
  }

  void Finish() {
    if (info_->scans_sampled > 0 && info_->decode_error.empty())
      info_->points_per_scan = double(points_) / info_->scans_sampled;
  }

 private:
  void Record(const StatusOr<Scan>& scan, const DecodeStats& stats) {
    if (!scan.ok()) return Fail(scan.status().message());
    info_->lidar_layout = stats.layout;
    info_->header_stamp = stats.stamp_is_end ? "end" : "start";
    points_ += static_cast<int64_t>(scan->points.size());
    ++info_->scans_sampled;
  }

  void Fail(const std::string& why) {
    info_->lidar_layout = "unknown";
    info_->decode_error = why;
    done_ = true;
  }

  BagTopicInfo* info_;
  LidarOptions lidar_;
  int64_t points_ = 0;
  bool done_ = false;
};

void SetRate(BagTopicInfo* info, TimeNs first_ns, TimeNs last_ns) {
  if (info->count < 2) return;
  const double span = NsToSeconds(last_ns - first_ns);
  if (span > 0.0) info->rate_hz = double(info->count - 1) / span;
}

// ---------------------------------------------------------------------------
// ROS1

void DescribeCloudTopic(const rosbag::Bag& bag, BagTopicInfo* info) {
  CloudSampler sampler(info);
  rosbag::View view(bag, rosbag::TopicQuery(info->topic));
  std::vector<uint8_t> bytes;
  for (const rosbag::MessageInstance& m : view) {
    if (sampler.Full()) break;
    const bool livox = m.getDataType() == kLivoxRos1Type;
    if (!livox && m.getMD5Sum() != bag_detail::kPointCloud2Md5) break;
    const size_t size = bag_detail::ReadRawMessage(m, &bytes);
    if (livox)
      sampler.Add(ParseLivoxRos1(bytes.data(), size, info->topic));
    else
      sampler.Add(bag_detail::ParseRos1PointCloud2(bytes.data(), size, info->topic,
                                                    "topic '" + info->topic + "'"));
  }
  sampler.Finish();
}

bool IsRos1ScanType(const std::string& type) {
  return type == bag_detail::kPointCloud2Type || type == kLivoxRos1Type;
}

// The type --lidar-topic must have: the topic's own when it is a LiDAR type.
std::string LidarTypeOf(const std::map<std::string, std::string>& topics, const std::string& topic,
                        const char* livox_type, const char* cloud_type) {
  auto it = topics.find(topic);
  return it != topics.end() && it->second == livox_type ? livox_type : cloud_type;
}

BagTopicInfo DescribeTopic(const rosbag::Bag& bag, const std::string& topic,
                           const std::string& type, bool decode_clouds) {
  BagTopicInfo info;
  info.topic = topic;
  info.type = type;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  info.count = view.size();
  if (info.count > 0)
    SetRate(&info, bag_detail::ToNs(view.getBeginTime()), bag_detail::ToNs(view.getEndTime()));
  if (decode_clouds && IsRos1ScanType(type)) DescribeCloudTopic(bag, &info);
  return info;
}

StatusOr<BagInfo> Describe(const std::string& path, const rosbag::Bag& bag,
                           const std::string& lidar_topic) {
  const auto topics = bag_detail::TopicTypes(bag);
  if (!lidar_topic.empty()) {
    Status s = bag_detail::RequireTopic(
        path, topics, lidar_topic,
        LidarTypeOf(topics, lidar_topic, kLivoxRos1Type, bag_detail::kPointCloud2Type),
        "--lidar-topic");
    if (!s.ok()) return s;
  }
  BagInfo info;
  info.path = path;
  info.storage = "ros1";
  rosbag::View all(bag);
  info.messages = all.size();
  if (info.messages > 0) {
    info.start_ns = bag_detail::ToNs(all.getBeginTime());
    info.end_ns = bag_detail::ToNs(all.getEndTime());
    info.start_s = NsToSeconds(info.start_ns);
    info.end_s = NsToSeconds(info.end_ns);
  }
  for (const auto& [topic, type] : topics) {
    const bool decode = lidar_topic.empty() || lidar_topic == topic;
    info.topics.push_back(DescribeTopic(bag, topic, type, decode));
  }
  return info;
}

// ROS1 bag format 2.0: after the "#ROSBAG V2.0\n" line, records of
// header_len (u32 LE), header fields (u32 length + "name=value"), data_len
// (u32), data. Chunk records (op 0x05) name their "compression" (none, bz2,
// lz4). Walks the record headers only (one seek per record) up to the index.
std::vector<std::string> Ros1ChunkCompressions(const std::string& path) {
  std::vector<std::string> found;
  std::ifstream in(path, std::ios::binary);
  in.seekg(13);
  auto u32 = [&in](uint32_t* v) {
    unsigned char b[4];
    if (!in.read(reinterpret_cast<char*>(b), 4)) return false;
    *v = b[0] | (b[1] << 8) | (b[2] << 16) | (uint32_t{b[3]} << 24);
    return true;
  };
  constexpr uint32_t kMaxHeader = 1 << 20;
  uint32_t header_len = 0, data_len = 0;
  while (u32(&header_len) && header_len <= kMaxHeader) {
    std::string header(header_len, '\0');
    if (!in.read(header.data(), header_len) || !u32(&data_len)) break;
    std::map<std::string, std::string> fields;
    for (size_t at = 0; at + 4 <= header.size();) {
      uint32_t n = 0;
      std::memcpy(&n, header.data() + at, 4);  // little endian on every supported host
      if (n > header.size() - at - 4) break;
      const std::string field = header.substr(at + 4, n);
      const size_t eq = field.find('=');
      if (eq != std::string::npos) fields[field.substr(0, eq)] = field.substr(eq + 1);
      at += 4 + n;
    }
    const std::string op = fields["op"];
    if (op == std::string(1, '\x05')) {
      const std::string& c = fields["compression"];
      if (std::find(found.begin(), found.end(), c) == found.end()) found.push_back(c);
    } else if (op == std::string(1, '\x07') || op == std::string(1, '\x06')) {
      break;  // connection or chunk-info records: the index section, no chunks after
    }
    in.seekg(data_len, std::ios::cur);
  }
  return found;
}

StatusOr<BagInfo> ReadRos1Info(const std::string& path, const std::string& lidar_topic) {
  rosbag::Bag bag;
  if (Status s = bag_detail::OpenForRead(path, &bag); !s.ok()) return s;
  try {
    StatusOr<BagInfo> info = Describe(path, bag, lidar_topic);
    if (info.ok()) info->compressions = Ros1ChunkCompressions(path);
    return info;
  } catch (const std::exception& e) {
    return Status::InvalidInput("reading bag '" + path + "' failed (" + e.what() +
                                "); truncated or corrupt?");
  }
}

// ---------------------------------------------------------------------------
// ROS 2

bool IsRos2ScanType(const std::string& type) {
  return type == cdr::kPointCloud2Type || type == kLivoxRos2Type;
}

// Samples the first clouds of one topic from a fresh source.
Status DescribeRos2Cloud(const std::string& path, int topic, BagTopicInfo* info) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  if (!source.ok()) return source.status();
  if (Status s = (*source)->SetTopicFilter({topic}); !s.ok()) return s;
  CloudSampler sampler(info);
  RawMessage m;
  while (!sampler.Full()) {
    StatusOr<bool> got = (*source)->Next(&m);
    if (!got.ok()) return got.status();
    if (!*got) break;
    if (info->type == kLivoxRos2Type)
      sampler.Add(cdr::DecodeLivoxCustomMsg(m.data.data(), m.data.size(), info->topic));
    else
      sampler.Add(cdr::DecodePointCloud2(m.data.data(), m.data.size(), info->topic));
  }
  sampler.Finish();
  return Status::Ok();
}

StatusOr<BagInfo> ReadRos2Info(const std::string& path, const std::string& lidar_topic) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  if (!source.ok()) return source.status();
  const std::vector<RecordingTopic>& topics = (*source)->topics();
  std::map<std::string, std::string> types;
  for (const RecordingTopic& t : topics) types[t.name] = t.type;
  if (!lidar_topic.empty()) {
    Status s = bag_detail::RequireTopic(
        path, types, lidar_topic,
        LidarTypeOf(types, lidar_topic, kLivoxRos2Type, cdr::kPointCloud2Type), "--lidar-topic");
    if (!s.ok()) return s;
  }
  StatusOr<std::vector<RecordingTopicStats>> stats = (*source)->TopicStats();
  if (!stats.ok()) return stats.status();
  BagInfo info;
  info.path = path;
  info.storage = (*source)->storage();
  info.compressions = (*source)->compressions();
  bool any = false;
  for (size_t i = 0; i < topics.size(); ++i) {
    const RecordingTopicStats& st = (*stats)[i];
    BagTopicInfo t;
    t.topic = topics[i].name;
    t.type = topics[i].type;
    t.count = st.count;
    SetRate(&t, st.first_ns, st.last_ns);
    const bool decode = lidar_topic.empty() || lidar_topic == t.topic;
    if (decode && IsRos2ScanType(t.type) && t.count > 0) {
      if (Status s = DescribeRos2Cloud(path, static_cast<int>(i), &t); !s.ok()) return s;
    }
    info.topics.push_back(std::move(t));
    if (st.count == 0) continue;
    info.start_ns = any ? std::min(info.start_ns, st.first_ns) : st.first_ns;
    info.end_ns = any ? std::max(info.end_ns, st.last_ns) : st.last_ns;
    info.messages += st.count;
    any = true;
  }
  info.start_s = NsToSeconds(info.start_ns);
  info.end_s = NsToSeconds(info.end_ns);
  std::sort(info.topics.begin(), info.topics.end(),
            [](const BagTopicInfo& a, const BagTopicInfo& b) { return a.topic < b.topic; });
  info.warnings = (*source)->warnings();
  return info;
}

void SetSpan(BagInfo* info, int64_t messages, TimeNs start_ns, TimeNs end_ns) {
  info->messages = messages;
  if (messages == 0) return;
  info->start_ns = start_ns;
  info->end_ns = end_ns;
  info->start_s = NsToSeconds(start_ns);
  info->end_s = NsToSeconds(end_ns);
}

StatusOr<BagInfo> ReadRos1Span(const std::string& path) {
  rosbag::Bag bag;
  if (Status s = bag_detail::OpenForRead(path, &bag); !s.ok()) return s;
  try {
    BagInfo info;
    info.path = path;
    info.storage = "ros1";
    rosbag::View all(bag);
    SetSpan(&info, all.size(), bag_detail::ToNs(all.getBeginTime()),
            bag_detail::ToNs(all.getEndTime()));
    return info;
  } catch (const std::exception& e) {
    return Status::InvalidInput("reading bag '" + path + "' failed (" + e.what() +
                                "); truncated or corrupt?");
  }
}

StatusOr<BagInfo> ReadRos2Span(const std::string& path) {
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  if (!source.ok()) return source.status();
  StatusOr<RecordingTopicStats> span = (*source)->Span();
  if (!span.ok()) return span.status();
  BagInfo info;
  info.path = path;
  info.storage = (*source)->storage();
  SetSpan(&info, span->count, span->first_ns, span->last_ns);
  info.warnings = (*source)->warnings();
  return info;
}

// A capture: its UDP destination ports as topics ("udp port 7502",
// "N-byte datagrams"), capture times as receive times.
StatusOr<BagInfo> ReadPcapInfo(const std::string& path) {
  StatusOr<PcapReader> reader = PcapReader::Open(path);
  if (!reader.ok()) return reader.status();
  BagInfo info;
  info.path = path;
  info.storage = "pcap";
  std::map<std::pair<int, size_t>, RecordingTopicStats> ports;
  UdpDatagram d;
  TimeNs first_ns = 0, last_ns = 0;
  int64_t n = 0;
  while (true) {
    StatusOr<bool> got = reader->Next(&d);
    if (!got.ok()) return got.status();
    if (!*got) break;
    first_ns = n == 0 ? d.t_ns : std::min(first_ns, d.t_ns);
    last_ns = n == 0 ? d.t_ns : std::max(last_ns, d.t_ns);
    ++n;
    RecordingTopicStats& s = ports[{d.dst_port, d.payload.size()}];
    if (s.count++ == 0) s.first_ns = d.t_ns;
    s.last_ns = d.t_ns;
  }
  SetSpan(&info, n, first_ns, last_ns);
  for (const auto& [key, s] : ports) {
    BagTopicInfo t;
    t.topic = "udp port " + std::to_string(key.first);
    t.type = std::to_string(key.second) + "-byte datagrams";
    t.count = s.count;
    SetRate(&t, s.first_ns, s.last_ns);
    info.topics.push_back(t);
  }
  return info;
}

}  // namespace

StatusOr<BagInfo> ReadBagSpan(const std::string& path) {
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  if (*kind == RecordingKind::kPcap) return ReadPcapInfo(path);
  if (*kind == RecordingKind::kRos1Bag) return ReadRos1Span(path);
  return ReadRos2Span(path);
}

StatusOr<BagInfo> ReadBagInfo(const std::string& path, const std::string& lidar_topic,
                              const std::string& ouster_metadata) {
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  StatusOr<BagInfo> info = *kind == RecordingKind::kPcap     ? ReadPcapInfo(path)
                           : *kind == RecordingKind::kRos1Bag ? ReadRos1Info(path, lidar_topic)
                                                              : ReadRos2Info(path, lidar_topic);
  if (!info.ok()) return info;
  StatusOr<bool> packets = bag_detail::HoldsOusterPackets(path, *kind, lidar_topic);
  if (!packets.ok()) return packets.status();
  if (!*packets) return info;
  StatusOr<OusterRecordingInfo> ouster =
      bag_detail::ReadOusterRecordingInfo(path, *kind, ouster_metadata);
  if (!ouster.ok()) return ouster.status();
  info->ouster = *ouster;
  return info;
}

}  // namespace rvlio
