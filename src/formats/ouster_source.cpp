// Ouster packet sources (ouster_source.h): a pcap capture with its metadata
// JSON, a ROS1 packet bag (rosbag_storage), a ROS 2 packet bag (formats/recording).
#include "ouster_source.h"

#include <algorithm>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "ros1_raw_message.h"
#include "rosbag_common.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/pcap.h"

namespace rvlio::bag_detail {
namespace {

namespace fs = std::filesystem;

const char* const kRos1PacketType = OusterPacketRos1Message::type();
constexpr const char* kRos2PacketTypes[] = {"ouster_sensor_msgs/msg/PacketMsg",
                                           "ouster_msgs/msg/PacketMsg"};
constexpr const char* kRos1StringType = "std_msgs/String";
// A UDP datagram this large on no known port is taken for a lidar packet (IMU
// packets are 48 bytes): the capture then fails on its size, not silently.
constexpr size_t kLidarLikeBytes = 1000;

bool InRange(const std::optional<ReceiveTimeRange>& range, TimeNs t_ns) {
  return !range || (t_ns >= range->first_ns && t_ns <= range->last_ns);
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// ---------------------------------------------------------------------------
// pcap

class PcapSource final : public OusterPacketSource {
 public:
  PcapSource(std::string path, PcapReader reader, OusterMetadata meta, std::string meta_path,
             std::optional<ReceiveTimeRange> range)
      : OusterPacketSource(std::move(path)), reader_(std::move(reader)), meta_(std::move(meta)),
        meta_path_(std::move(meta_path)), range_(range),
        lidar_bytes_(static_cast<size_t>(OusterFormatOf(meta_).PacketBytes())) {}

  StatusOr<bool> Next(OusterRawPacket* out) override {
    UdpDatagram d;
    while (true) {
      StatusOr<bool> got = reader_.Next(&d);
      if (!got.ok() || !*got) return got;
      std::optional<OusterPacketKind> kind;
      if (Status s = Classify(d, &kind); !s.ok()) return s;
      if (!kind || !InRange(range_, d.t_ns)) continue;
      out->kind = *kind;
      out->receive_ns = d.t_ns;
      out->bytes = std::move(d.payload);
      return true;
    }
  }

  const OusterMetadata& metadata() const override { return meta_; }
  std::string storage() const override { return "pcap"; }
  std::string metadata_origin() const override { return meta_path_; }
  std::string lidar_origin() const override { return Origin(lidar_); }
  std::string imu_origin() const override { return Origin(imu_); }

 private:
  struct Stream {
    bool known = false;
    std::string src;
    uint16_t port = 0;
  };
  static std::string Origin(const Stream& s) {
    return s.known ? "udp " + s.src + " port " + std::to_string(s.port) : "none";
  }

  // Lidar: the metadata's packet size, its lidar port, or any large
  // datagram; IMU: the IMU profile's packet size or the metadata's IMU port. One sensor only.
  Status Classify(const UdpDatagram& d, std::optional<OusterPacketKind>* kind) {
    const size_t n = d.payload.size();
    const bool lidar = n == lidar_bytes_ || n > kLidarLikeBytes ||
                       (meta_.udp_port_lidar != 0 && d.dst_port == meta_.udp_port_lidar);
    const bool imu = !lidar && (n == static_cast<size_t>(OusterImuPacketBytes(meta_)) ||
                                (meta_.udp_port_imu != 0 && d.dst_port == meta_.udp_port_imu));
    if (!lidar && !imu) return Status::Ok();
    Stream& s = lidar ? lidar_ : imu_;
    if (!s.known) {
      s = {true, d.src, d.dst_port};
    } else if (s.port != d.dst_port || s.src != d.src) {
      return Status::InvalidInput("capture '" + path_ + "' holds " + (lidar ? "lidar" : "IMU") +
                                  " packets from two sensors (" + Origin(s) + " and udp " + d.src +
                                  " port " + std::to_string(d.dst_port) +
                                  "); rvlio reads one sensor: split the capture by port");
    }
    *kind = lidar ? OusterPacketKind::kLidar : OusterPacketKind::kImu;
    return Status::Ok();
  }

  PcapReader reader_;
  OusterMetadata meta_;
  std::string meta_path_;
  std::optional<ReceiveTimeRange> range_;
  size_t lidar_bytes_;
  Stream lidar_, imu_;
};

// ---------------------------------------------------------------------------
// Packet bags: topic choice and metadata shared by ROS1 and ROS 2.

struct PacketTopics {
  std::string lidar, imu, metadata;
};

// The packet topics ("…lidar_packets", "…imu_packets") and the metadata
// String topic ("…metadata"); InvalidInput for two sensors' lidar topics.
StatusOr<PacketTopics> ChoosePacketTopics(const std::string& path,
                                          const std::map<std::string, std::string>& types,
                                          const std::string& string_type) {
  PacketTopics t;
  std::vector<std::string> lidar, imu, meta;
  for (const auto& [topic, type] : types) {
    if (IsOusterPacketType(type) && EndsWith(topic, "lidar_packets")) lidar.push_back(topic);
    if (IsOusterPacketType(type) && EndsWith(topic, "imu_packets")) imu.push_back(topic);
    if (type == string_type && EndsWith(topic, "metadata")) meta.push_back(topic);
  }
  if (lidar.size() > 1 || imu.size() > 1)
    return Status::InvalidInput("bag '" + path + "' holds packet topics of several sensors (" +
                                DescribeTopics(types) + "); rvlio reads one sensor");
  if (lidar.empty())
    return Status::InvalidInput("bag '" + path + "' has no Ouster lidar_packets topic; topics present: " +
                                DescribeTopics(types));
  t.lidar = lidar[0];
  if (!imu.empty()) t.imu = imu[0];
  if (meta.size() == 1) t.metadata = meta[0];
  return t;
}

Status NoMetadata(const std::string& path) {
  return Status::InvalidInput("bag '" + path + "' has no Ouster metadata topic (a std_msgs String "
                              "topic named …/metadata); give the sensor's JSON with "
                              "--ouster-metadata FILE");
}

// The metadata a bag's reader was given (--ouster-metadata) instead of its topic.
Status LoadMetadataFile(const std::string& path, OusterMetadata* meta, std::string* origin) {
  *origin = path;
  StatusOr<OusterMetadata> m = ReadOusterMetadataFile(path);
  if (!m.ok()) return m.status();
  *meta = *m;
  return Status::Ok();
}

StatusOr<std::vector<uint8_t>> Ros1Bytes(const std::vector<uint8_t>& raw, const std::string& where) {
  return Ros1PacketBuffer(raw.data(), raw.size(), where);
}

class Ros1Source final : public OusterPacketSource {
 public:
  explicit Ros1Source(std::string path) : OusterPacketSource(std::move(path)) {}

  Status Init(const std::string& metadata_path, const std::optional<ReceiveTimeRange>& range) {
    if (Status s = OpenForRead(path_, &bag_); !s.ok()) return s;
    try {
      StatusOr<PacketTopics> topics = ChoosePacketTopics(path_, TopicTypes(bag_), kRos1StringType);
      if (!topics.ok()) return topics.status();
      topics_ = *topics;
      if (Status s = LoadMetadata(metadata_path); !s.ok()) return s;
      std::vector<std::string> names{topics_.lidar};
      if (!topics_.imu.empty()) names.push_back(topics_.imu);
      view_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(names));
      it_ = view_->begin();
      range_ = range;
    } catch (const std::exception& e) {
      return ReadError(e);
    }
    return Status::Ok();
  }

  StatusOr<bool> Next(OusterRawPacket* out) override {
    try {
      while (it_ != view_->end()) {
        const rosbag::MessageInstance m = *it_;  // a copy: the iterator owns *it_
        ++it_;
        const TimeNs t = ToNs(m.getTime());
        if (!InRange(range_, t)) continue;
        const std::string where = "topic '" + m.getTopic() + "' in bag '" + path_ + "'";
        StatusOr<std::vector<uint8_t>> bytes = Ros1Bytes(RawMessageBytes(m), where);
        if (!bytes.ok()) return bytes.status();
        out->kind = m.getTopic() == topics_.lidar ? OusterPacketKind::kLidar : OusterPacketKind::kImu;
        out->receive_ns = t;
        out->bytes = std::move(bytes).value();
        TrimDriverByte(meta_, out->kind, &out->bytes);
        return true;
      }
    } catch (const std::exception& e) {
      return ReadError(e);
    }
    return false;
  }

  const OusterMetadata& metadata() const override { return meta_; }
  std::string storage() const override { return "ros1"; }
  std::string metadata_origin() const override { return meta_origin_; }
  std::string lidar_origin() const override { return topics_.lidar; }
  std::string imu_origin() const override { return topics_.imu.empty() ? "none" : topics_.imu; }

 private:
  Status ReadError(const std::exception& e) const {
    return Status::InvalidInput("reading bag '" + path_ + "' failed (" + e.what() +
                                "); truncated or corrupt?");
  }

  Status LoadMetadata(const std::string& metadata_path) {
    if (!metadata_path.empty()) return LoadMetadataFile(metadata_path, &meta_, &meta_origin_);
    if (topics_.metadata.empty()) return NoMetadata(path_);
    meta_origin_ = "topic " + topics_.metadata;
    rosbag::View view(bag_, rosbag::TopicQuery(topics_.metadata));
    for (const rosbag::MessageInstance& m : view) {
      const std::string where = "topic '" + topics_.metadata + "' in bag '" + path_ + "'";
      StatusOr<std::vector<uint8_t>> text = Ros1Bytes(RawMessageBytes(m), where);
      if (!text.ok()) return text.status();
      StatusOr<OusterMetadata> meta =
          ParseOusterMetadata(std::string(text->begin(), text->end()), where);
      if (!meta.ok()) return meta.status();
      meta_ = *meta;
      return Status::Ok();
    }
    return NoMetadata(path_);
  }

  rosbag::Bag bag_;
  PacketTopics topics_;
  OusterMetadata meta_;
  std::string meta_origin_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  std::optional<ReceiveTimeRange> range_;
};

class Ros2Source final : public OusterPacketSource {
 public:
  explicit Ros2Source(std::string path) : OusterPacketSource(std::move(path)) {}

  Status Init(const std::string& metadata_path, const std::optional<ReceiveTimeRange>& range) {
    StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path_);
    if (!source.ok()) return source.status();
    source_ = std::move(source).value();
    std::map<std::string, std::string> types;
    for (const RecordingTopic& t : source_->topics()) types[t.name] = t.type;
    StatusOr<PacketTopics> topics = ChoosePacketTopics(path_, types, cdr::kStringType);
    if (!topics.ok()) return topics.status();
    topics_ = *topics;
    const auto& all = source_->topics();
    for (size_t i = 0; i < all.size(); ++i) {
      if (all[i].name == topics_.lidar) lidar_index_ = static_cast<int>(i);
      if (all[i].name == topics_.imu) imu_index_ = static_cast<int>(i);
      if (all[i].name == topics_.metadata) meta_index_ = static_cast<int>(i);
    }
    if (Status s = LoadMetadata(metadata_path); !s.ok()) return s;
    // LoadMetadata read the metadata topic; a fresh source streams the packets.
    source = RecordingSource::Open(path_);
    if (!source.ok()) return source.status();
    source_ = std::move(source).value();
    std::vector<int> filter{lidar_index_};
    if (imu_index_ >= 0) filter.push_back(imu_index_);
    if (Status s = source_->SetTopicFilter(filter); !s.ok()) return s;
    if (range)
      if (Status s = source_->SetTimeFilter(range->first_ns, range->last_ns); !s.ok()) return s;
    return Status::Ok();
  }

  StatusOr<bool> Next(OusterRawPacket* out) override {
    RawMessage m;
    StatusOr<bool> got = source_->Next(&m);
    if (!got.ok() || !*got) return got;
    const bool lidar = m.topic == lidar_index_;
    const std::string where = "topic '" + (lidar ? topics_.lidar : topics_.imu) + "' in bag '" + path_ + "'";
    StatusOr<std::vector<uint8_t>> bytes = CdrPacketBuffer(m.data.data(), m.data.size(), where);
    if (!bytes.ok()) return bytes.status();
    out->kind = lidar ? OusterPacketKind::kLidar : OusterPacketKind::kImu;
    out->receive_ns = m.stamp_ns;
    out->bytes = std::move(bytes).value();
    TrimDriverByte(meta_, out->kind, &out->bytes);
    return true;
  }

  const OusterMetadata& metadata() const override { return meta_; }
  std::string storage() const override { return source_->storage(); }
  std::string metadata_origin() const override { return meta_origin_; }
  std::string lidar_origin() const override { return topics_.lidar; }
  std::string imu_origin() const override { return topics_.imu.empty() ? "none" : topics_.imu; }

 private:
  Status LoadMetadata(const std::string& metadata_path) {
    if (!metadata_path.empty()) return LoadMetadataFile(metadata_path, &meta_, &meta_origin_);
    if (meta_index_ < 0) return NoMetadata(path_);
    meta_origin_ = "topic " + topics_.metadata;
    if (Status s = source_->SetTopicFilter({meta_index_}); !s.ok()) return s;
    RawMessage m;
    StatusOr<bool> got = source_->Next(&m);
    if (!got.ok()) return got.status();
    if (!*got) return NoMetadata(path_);
    const std::string where = "topic '" + topics_.metadata + "' in bag '" + path_ + "'";
    cdr::Reader r(m.data.data(), m.data.size(), where);
    std::string text;
    if (Status s = r.Begin(); !s.ok()) return s;
    if (Status s = r.String(&text, "data"); !s.ok()) return s;
    StatusOr<OusterMetadata> meta = ParseOusterMetadata(text, where);
    if (!meta.ok()) return meta.status();
    meta_ = *meta;
    return Status::Ok();
  }

  std::unique_ptr<RecordingSource> source_;
  PacketTopics topics_;
  int lidar_index_ = -1, imu_index_ = -1, meta_index_ = -1;
  OusterMetadata meta_;
  std::string meta_origin_;
};

}  // namespace

bool IsOusterPacketType(const std::string& type) {
  if (type == kRos1PacketType) return true;
  return std::find(std::begin(kRos2PacketTypes), std::end(kRos2PacketTypes), type) !=
         std::end(kRos2PacketTypes);
}

std::vector<std::string> OusterPacketTypes(bool ros2) {
  if (!ros2) return {kRos1PacketType};
  return {std::begin(kRos2PacketTypes), std::end(kRos2PacketTypes)};
}

// ROS1: uint8[] buf = uint32 length + bytes (a String too: length + chars).
StatusOr<std::vector<uint8_t>> Ros1PacketBuffer(const uint8_t* data, size_t size,
                                                const std::string& where) {
  if (size < 4) return Status::InvalidInput(where + ": message shorter than its length field");
  const uint32_t n = uint32_t{data[0]} | uint32_t{data[1]} << 8 | uint32_t{data[2]} << 16 |
                     uint32_t{data[3]} << 24;
  if (n != size - 4)
    return Status::InvalidInput(where + ": message of " + std::to_string(size) +
                                " bytes holds a buffer length of " + std::to_string(n));
  return std::vector<uint8_t>(data + 4, data + size);
}

StatusOr<std::vector<uint8_t>> CdrPacketBuffer(const uint8_t* data, size_t size,
                                               const std::string& where) {
  cdr::Reader r(data, size, where);
  const uint8_t* bytes = nullptr;
  size_t n = 0;
  if (Status s = r.Begin(); !s.ok()) return s;
  if (Status s = r.ByteSequence(&bytes, &n, "buf"); !s.ok()) return s;
  return std::vector<uint8_t>(bytes, bytes + n);
}

void TrimDriverByte(const OusterMetadata& meta, OusterPacketKind kind, std::vector<uint8_t>* bytes) {
  const size_t want = kind == OusterPacketKind::kLidar
                          ? static_cast<size_t>(OusterFormatOf(meta).PacketBytes())
                          : static_cast<size_t>(OusterImuPacketBytes(meta));
  if (bytes->size() == want + 1) bytes->pop_back();
}

bool UsesOusterPackets(const std::map<std::string, std::string>& topic_types,
                       const std::string& lidar_topic) {
  bool packets = false;
  for (const auto& [topic, type] : topic_types) packets = packets || IsOusterPacketType(type);
  auto it = topic_types.find(lidar_topic);
  return packets && (it == topic_types.end() || IsOusterPacketType(it->second));
}

StatusOr<bool> HoldsOusterPackets(const std::string& path, RecordingKind kind,
                                  const std::string& lidar_topic) {
  if (kind == RecordingKind::kPcap) return true;
  if (kind == RecordingKind::kRos1Bag) {
    rosbag::Bag bag;
    if (Status s = OpenForRead(path, &bag); !s.ok()) return s;
    try {
      return UsesOusterPackets(TopicTypes(bag), lidar_topic);
    } catch (const std::exception& e) {
      return Status::InvalidInput("reading bag '" + path + "' failed (" + e.what() +
                                  "); truncated or corrupt?");
    }
  }
  StatusOr<std::unique_ptr<RecordingSource>> source = RecordingSource::Open(path);
  if (!source.ok()) return source.status();
  std::map<std::string, std::string> types;
  for (const RecordingTopic& t : (*source)->topics()) types[t.name] = t.type;
  return UsesOusterPackets(types, lidar_topic);
}

StatusOr<std::string> FindOusterMetadata(const std::string& pcap_path,
                                         const std::string& explicit_path) {
  if (!explicit_path.empty()) return explicit_path;
  const fs::path pcap(pcap_path);
  const fs::path dir = pcap.has_parent_path() ? pcap.parent_path() : fs::path(".");
  const std::string stem = pcap.stem().string();
  for (const std::string& name : {stem + ".json", stem + "_0.json"}) {
    std::error_code ec;
    if (fs::is_regular_file(dir / name, ec)) return (dir / name).string();
  }
  std::string best;
  size_t best_prefix = 0;
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const fs::path p = e.path();
    if (p.extension() != ".json") continue;
    const std::string prefix = p.stem().string() + "_";
    if (stem.compare(0, prefix.size(), prefix) == 0 && prefix.size() > best_prefix &&
        e.is_regular_file(ec)) {
      best = p.string();
      best_prefix = prefix.size();
    }
  }
  if (!best.empty()) return best;
  return Status::InvalidInput("capture '" + pcap_path + "' has no Ouster metadata: no " + stem +
                              ".json, " + stem + "_0.json or NAME.json with " + stem +
                              " starting NAME_ next to it; give it with --ouster-metadata FILE");
}

StatusOr<std::unique_ptr<OusterPacketSource>> OpenOusterPcapSource(
    const std::string& path, const std::string& metadata_path,
    const std::optional<ReceiveTimeRange>& range) {
  StatusOr<PcapReader> reader = PcapReader::Open(path);
  if (!reader.ok()) return reader.status();
  StatusOr<std::string> meta_path = FindOusterMetadata(path, metadata_path);
  if (!meta_path.ok()) return meta_path.status();
  StatusOr<OusterMetadata> meta = ReadOusterMetadataFile(*meta_path);
  if (!meta.ok()) return meta.status();
  return std::unique_ptr<OusterPacketSource>(std::make_unique<PcapSource>(
      path, std::move(reader).value(), *meta, *meta_path, range));
}

StatusOr<std::unique_ptr<OusterPacketSource>> OpenOusterBagSource(
    const std::string& path, RecordingKind kind, const std::string& metadata_path,
    const std::optional<ReceiveTimeRange>& range) {
  if (kind == RecordingKind::kRos1Bag) {
    auto source = std::make_unique<Ros1Source>(path);
    if (Status s = source->Init(metadata_path, range); !s.ok()) return s;
    return std::unique_ptr<OusterPacketSource>(std::move(source));
  }
  auto source = std::make_unique<Ros2Source>(path);
  if (Status s = source->Init(metadata_path, range); !s.ok()) return s;
  return std::unique_ptr<OusterPacketSource>(std::move(source));
}

}  // namespace rvlio::bag_detail

namespace rvlio {

StatusOr<OusterMetadata> ReadOusterMetadataFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::InvalidInput("cannot read Ouster metadata '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseOusterMetadata(text.str(), path);
}

}  // namespace rvlio
