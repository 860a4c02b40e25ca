// SensorBagWriter for ROS 2 recordings: CDR messages (formats/cdr) in a single
// .mcap (formats/mcap) or a single sqlite3 .db3 with the tables rosbag2 creates.
// Both write to path + ".tmp" and rename on Close().
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>

#include <sqlite3.h>

#include "rvlio/formats/atomic_file.h"
#include "rvlio/formats/cdr.h"
#include "rvlio/formats/livox.h"
#include "rvlio/formats/mcap.h"
#include "rvlio/formats/sensor_bag.h"
#include "sensor_writer_common.h"

namespace rvlio::bag_detail {
namespace {

// builtin_interfaces/Time holds int32 seconds.
constexpr TimeNs kMaxRos2Ns = static_cast<TimeNs>(std::numeric_limits<int32_t>::max()) * kNsPerSecond;

Status CheckRos2Stamp(TimeNs t_ns, const std::string& what) {
  return CheckStamp(t_ns, kMaxRos2Ns, "ROS 2 time range [0, 2^31 s)", what);
}

// One ROS 2 storage: topics with their type and definition, messages with a
// receive time.
class Ros2Storage {
 public:
  virtual ~Ros2Storage() = default;
  virtual StatusOr<int64_t> AddTopic(const std::string& topic, const std::string& type,
                                     const std::string& definition) = 0;
  virtual Status Write(int64_t topic_id, TimeNs log_time_ns, const std::vector<uint8_t>& data) = 0;
  virtual Status Close() = 0;
};

class McapStorage final : public Ros2Storage {
 public:
  static StatusOr<std::unique_ptr<Ros2Storage>> Create(const std::string& path,
                                                       const std::string& compression) {
    mcap::WriterOptions options;
    if (compression == "unchunked") {
      options.chunked = false;
      options.compression = "";
    } else if (compression == "zstd" || compression == "lz4" || compression == "none") {
      options.compression = compression == "none" ? "" : compression;
    } else {
      return Status::InvalidInput("MCAP compression '" + compression +
                                  "' is not one of zstd, lz4, none, unchunked");
    }
    StatusOr<std::unique_ptr<mcap::Writer>> writer = mcap::Writer::Create(path, options);
    if (!writer.ok()) return writer.status();
    auto storage = std::make_unique<McapStorage>();
    storage->writer_ = std::move(writer).value();
    return std::unique_ptr<Ros2Storage>(std::move(storage));
  }

  StatusOr<int64_t> AddTopic(const std::string& topic, const std::string& type,
                             const std::string& definition) override {
    StatusOr<uint16_t> schema = writer_->AddSchema(type, "ros2msg", definition);
    if (!schema.ok()) return schema.status();
    StatusOr<uint16_t> channel = writer_->AddChannel(*schema, topic, "cdr");
    if (!channel.ok()) return channel.status();
    return static_cast<int64_t>(*channel);
  }

  Status Write(int64_t topic_id, TimeNs log_time_ns, const std::vector<uint8_t>& data) override {
    mcap::Message m;
    m.channel_id = static_cast<uint16_t>(topic_id);
    m.sequence = ++sequence_;
    m.log_time_ns = static_cast<uint64_t>(log_time_ns);
    m.publish_time_ns = m.log_time_ns;
    m.data = data;
    return writer_->Write(m);
  }

  Status Close() override { return writer_->Close(); }

 private:
  std::unique_ptr<mcap::Writer> writer_;
  uint32_t sequence_ = 0;
};

// The schema of rosbag2's sqlite3 storage (schema version 4).
constexpr const char* kDb3Schema =
    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);"
    "INSERT INTO schema VALUES(4,'rvlio');"
    "CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,"
    "metadata TEXT NOT NULL);"
    "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
    "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,"
    "type_description_hash TEXT NOT NULL);"
    "CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT NULL,"
    "encoding TEXT NOT NULL,encoded_message_definition TEXT NOT NULL,"
    "type_description_hash TEXT NOT NULL);"
    "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
    "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
    "CREATE INDEX timestamp_idx ON messages (timestamp ASC);";

class Db3Storage final : public Ros2Storage {
 public:
  Db3Storage(std::string path) : path_(std::move(path)), target_(path_), tmp_(path_ + ".tmp") {}
  ~Db3Storage() override {
    if (db_ == nullptr) return;
    CloseDb();
    std::remove(tmp_.c_str());
  }

  Status Init() {
    // The file replaced: the path or a link's final target (never a FIFO or a device).
    StatusOr<std::string> target = ResolveOutputFile(path_);
    if (!target.ok()) return target.status();
    target_ = *target;
    tmp_ = target_ + ".tmp";
    std::remove(tmp_.c_str());  // a leftover of an interrupted run
    if (sqlite3_open_v2(tmp_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                        nullptr) != SQLITE_OK)
      return Error("cannot create");
    if (Status s = Exec(kDb3Schema); !s.ok()) return s;
    if (Status s = Exec("BEGIN"); !s.ok()) return s;
    if (sqlite3_prepare_v2(db_, "INSERT INTO messages(topic_id,timestamp,data) VALUES(?,?,?)", -1,
                           &insert_, nullptr) != SQLITE_OK)
      return Error("cannot prepare a message insert for");
    return Status::Ok();
  }

  StatusOr<int64_t> AddTopic(const std::string& topic, const std::string& type,
                             const std::string& definition) override {
    const int64_t id = ++topics_;
    sqlite3_stmt* q = nullptr;
    Status s = Prepare("INSERT INTO topics VALUES(?,?,?,'cdr','','')", &q);
    if (s.ok()) {
      sqlite3_bind_int64(q, 1, id);
      sqlite3_bind_text(q, 2, topic.c_str(), -1, SQLITE_TRANSIENT);
      sqlite3_bind_text(q, 3, type.c_str(), -1, SQLITE_TRANSIENT);
      s = Step(q);
    }
    if (s.ok() && defined_.insert({type, true}).second) {
      s = Prepare("INSERT INTO message_definitions(topic_type,encoding,"
                  "encoded_message_definition,type_description_hash) VALUES(?,'ros2msg',?,'')",
                  &q);
      if (s.ok()) {
        sqlite3_bind_text(q, 1, type.c_str(), -1, SQLITE_TRANSIENT);
        sqlite3_bind_text(q, 2, definition.c_str(), -1, SQLITE_TRANSIENT);
        s = Step(q);
      }
    }
    if (!s.ok()) return s;
    return id;
  }

  Status Write(int64_t topic_id, TimeNs log_time_ns, const std::vector<uint8_t>& data) override {
    sqlite3_reset(insert_);
    sqlite3_bind_int64(insert_, 1, topic_id);
    sqlite3_bind_int64(insert_, 2, log_time_ns);
    sqlite3_bind_blob64(insert_, 3, data.data(), data.size(), SQLITE_STATIC);
    if (sqlite3_step(insert_) != SQLITE_DONE) return Error("cannot write a message to");
    return Status::Ok();
  }

  Status Close() override {
    Status s = Exec("COMMIT");
    const bool closed = CloseDb();
    if (s.ok() && !closed) s = Status::InvalidInput("cannot close db3 '" + tmp_ + "'");
    if (s.ok() && std::rename(tmp_.c_str(), target_.c_str()) != 0)
      s = Status::InvalidInput("cannot rename '" + tmp_ + "' to '" + path_ +
                               "': " + std::strerror(errno));
    if (!s.ok()) std::remove(tmp_.c_str());
    return s;
  }

 private:
  Status Error(const std::string& what) const {
    const char* why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    return Status::InvalidInput(what + " db3 '" + tmp_ + "' (sqlite: " + why + ")");
  }
  Status Exec(const char* sql) {
    if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK)
      return Error("cannot write");
    return Status::Ok();
  }
  Status Prepare(const char* sql, sqlite3_stmt** q) {
    *q = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, q, nullptr) != SQLITE_OK) return Error("cannot write");
    return Status::Ok();
  }
  // Steps and finalizes a prepared statement.
  Status Step(sqlite3_stmt* q) {
    const int rc = sqlite3_step(q);
    sqlite3_finalize(q);
    return rc == SQLITE_DONE ? Status::Ok() : Error("cannot write");
  }
  bool CloseDb() {
    sqlite3_finalize(insert_);
    insert_ = nullptr;
    const bool ok = sqlite3_close(db_) == SQLITE_OK;
    db_ = nullptr;
    return ok;
  }

  std::string path_, target_, tmp_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  int64_t topics_ = 0;
  std::map<std::string, bool> defined_;  // types with a message_definitions row
};

class Ros2SensorWriter final : public SensorBagWriter {
 public:
  Ros2SensorWriter(std::string path, std::unique_ptr<Ros2Storage> storage)
      : path_(std::move(path)), storage_(std::move(storage)) {}

  Status WriteOusterScan(const std::string& topic, const std::string& frame_id, const Scan& scan,
                         int rows, int cols) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckRos2Stamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    OwnedCloud cloud;
    if (Status s = BuildOusterCloud(scan, rows, cols, &cloud); !s.ok()) return s;
    // Recorded when the driver publishes it: at the end of the sweep.
    return Write(topic, cdr::kPointCloud2Type, cdr::PointCloud2Definition(), scan.t_end_ns,
                 cdr::EncodePointCloud2(cloud.view, frame_id, cloud.is_dense));
  }

  Status WriteLivoxScan(const std::string& topic, const std::string& frame_id,
                        const Scan& scan) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(scan.t_start_ns, "scan start"); !s.ok()) return s;
    if (Status s = CheckRos2Stamp(scan.t_end_ns, "scan end"); !s.ok()) return s;
    if (scan.t_end_ns < scan.t_start_ns) return Status::InvalidInput("scan ends before it starts");
    // offset_time must fit uint32 ns after the timebase.
    if (Status s = CheckRelativePointTimes(scan); !s.ok()) return s;
    const LivoxCustomMsg msg = ScanToLivoxCustomMsg(scan, frame_id);
    return Write(topic, kLivoxRos2Type, cdr::LivoxCustomMsgDefinition(), scan.t_end_ns,
                 cdr::EncodeLivoxCustomMsg(msg));
  }

  Status WriteImu(const std::string& topic, const std::string& frame_id,
                  const ImuSample& sample) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(sample.t_ns, "IMU stamp"); !s.ok()) return s;
    cdr::ImuMessage msg;
    msg.header_stamp_ns = sample.t_ns;
    msg.frame_id = frame_id;
    msg.orientation_covariance[0] = -1.0;  // no orientation estimate
    msg.angular_velocity = {sample.gyro_imu.x(), sample.gyro_imu.y(), sample.gyro_imu.z()};
    msg.linear_acceleration = {sample.acc_imu.x(), sample.acc_imu.y(), sample.acc_imu.z()};
    return Write(topic, cdr::kImuType, cdr::ImuDefinition(), sample.t_ns, cdr::EncodeImu(msg));
  }

  Status WriteNavSatFix(const std::string& topic, const NavSatFix& fix) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(fix.header_stamp_ns, "NavSatFix stamp"); !s.ok()) return s;
    return Write(topic, kNavSatFixRos2Type, cdr::NavSatFixDefinition(), fix.header_stamp_ns,
                 EncodeNavSatFixCdr(fix));
  }

  Status WriteOusterPacket(const std::string& topic, TimeNs receive_ns,
                           const std::vector<uint8_t>& packet) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(receive_ns, "packet receive time"); !s.ok()) return s;
    cdr::Writer w;
    w.Bytes(packet.data(), packet.size());
    return Write(topic, "ouster_sensor_msgs/msg/PacketMsg", "uint8[] buf\n", receive_ns, w.Take());
  }

  Status WriteString(const std::string& topic, TimeNs receive_ns, const std::string& text) override {
    if (!storage_) return Closed();
    if (Status s = CheckRos2Stamp(receive_ns, "String receive time"); !s.ok()) return s;
    return Write(topic, cdr::kStringType, "string data\n", receive_ns, cdr::EncodeString(text));
  }

  Status Close() override {
    if (!storage_) return Closed();
    Status s = storage_->Close();
    storage_.reset();
    return s;
  }

 private:
  Status Closed() const { return Status::Internal("bag '" + path_ + "' is already closed"); }

  Status Write(const std::string& topic, const std::string& type, const std::string& definition,
               TimeNs log_time_ns, const std::vector<uint8_t>& data) {
    auto it = topic_ids_.find(topic);
    if (it == topic_ids_.end()) {
      StatusOr<int64_t> id = storage_->AddTopic(topic, type, definition);
      if (!id.ok()) return id.status();
      it = topic_ids_.emplace(topic, std::make_pair(*id, type)).first;
    } else if (it->second.second != type) {
      return Status::InvalidInput("topic '" + topic + "' of '" + path_ + "' already holds " +
                                  it->second.second + ", not " + type);
    }
    return storage_->Write(it->second.first, log_time_ns, data);
  }

  std::string path_;
  std::unique_ptr<Ros2Storage> storage_;
  std::map<std::string, std::pair<int64_t, std::string>> topic_ids_;  // topic -> (id, type)
};

}  // namespace

StatusOr<std::unique_ptr<SensorBagWriter>> CreateRos2Writer(const std::string& path,
                                                            const BagWriterOptions& options) {
  std::unique_ptr<Ros2Storage> storage;
  if (options.format == "mcap") {
    StatusOr<std::unique_ptr<Ros2Storage>> mcap = McapStorage::Create(path, options.mcap_compression);
    if (!mcap.ok()) return mcap.status();
    storage = std::move(mcap).value();
  } else {
    auto db3 = std::make_unique<Db3Storage>(path);
    if (Status s = db3->Init(); !s.ok()) return s;
    storage = std::move(db3);
  }
  return std::unique_ptr<SensorBagWriter>(std::make_unique<Ros2SensorWriter>(path, std::move(storage)));
}

}  // namespace rvlio::bag_detail
