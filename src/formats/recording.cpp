// Recording detection and the ROS 2 raw message sources: sqlite3 (.db3),
// MCAP (through formats/mcap) and bag folders (metadata.yaml, split bags).
#include "rvlio/formats/recording.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include "rvlio/formats/mcap.h"
#include "rvlio/formats/pcap.h"

namespace rvlio {
namespace {

namespace fs = std::filesystem;

constexpr char kRos1Magic[] = "#ROSBAG V2.0";
constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr char kSqliteMagic[] = "SQLite format 3";  // + NUL: 16 bytes
constexpr const char* kMetadataFile = "metadata.yaml";

bool StartsWith(const std::string& head, const char* magic, size_t n) {
  return head.size() >= n && std::memcmp(head.data(), magic, n) == 0;
}

StatusOr<RecordingKind> DetectDirectory(const std::string& path) {
  std::error_code ec;
  if (fs::is_regular_file(fs::path(path) / kMetadataFile, ec)) return RecordingKind::kRos2Folder;
  if (fs::is_empty(path, ec))
    return Status::InvalidInput("'" + path + "' is an empty directory, not a ROS 2 bag folder");
  return Status::InvalidInput("'" + path + "' is a directory, not a regular file, and not a "
                              "ROS 2 bag folder (no " + kMetadataFile + ")");
}

// ---------------------------------------------------------------------------
// sqlite3

// SQLite URI of a file opened read-only as immutable: SQLite then takes no
// locks and creates no -shm/-wal/-journal file next to it, so a recording on
// read-only storage, or in a folder the user cannot write, opens (rosbag2
// writes WAL-mode databases, whose plain read-only open needs a writable
// -shm), and reading never changes the recording's folder. The path is
// percent-encoded where the URI syntax needs it.
std::string ImmutableUri(const std::string& path) {
  std::string uri = "file:";
  if (!path.empty() && path[0] == '/') uri += "//";  // file:///abs/path
  for (const char c : path) {
    if (c == '%' || c == '?' || c == '#') {
      char hex[4];
      std::snprintf(hex, sizeof(hex), "%%%02X", static_cast<unsigned char>(c));
      uri += hex;
    } else {
      uri += c;
    }
  }
  return uri + "?mode=ro&immutable=1";
}

// A write-ahead log left next to a database (its writer did not close it):
// with immutable=1 its content is not read; say so.
std::vector<std::string> WalWarnings(const std::string& path) {
  std::error_code ec;
  const std::string wal = path + "-wal";
  if (!fs::is_regular_file(wal, ec) || fs::file_size(wal, ec) == 0 || ec) return {};
  return {"db3 '" + path + "' has a write-ahead log '" + wal +
          "' (the recording was not closed cleanly): messages only in it are not read"};
}

class SqliteSource final : public RecordingSource {
 public:
  explicit SqliteSource(std::string path) : path_(std::move(path)) {}
  ~SqliteSource() override {
    sqlite3_finalize(stmt_);
    sqlite3_close(db_);
  }

  Status Init() {
    if (sqlite3_open_v2(ImmutableUri(path_).c_str(), &db_, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI,
                        nullptr) != SQLITE_OK)
      return Error("cannot open");
    warnings_ = WalWarnings(path_);
    sqlite3_stmt* q = nullptr;
    if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics ORDER BY id",
                           -1, &q, nullptr) != SQLITE_OK)
      return Error("is not a ROS 2 bag (no readable topics table)");
    int rc;
    while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
      topic_index_[sqlite3_column_int64(q, 0)] = static_cast<int>(topics_.size());
      topics_.push_back({Text(q, 1), Text(q, 2), Text(q, 3)});
    }
    sqlite3_finalize(q);
    if (rc != SQLITE_DONE) return Error("reading the topics table failed");
    return Status::Ok();
  }

  const std::string& path() const override { return path_; }
  std::string storage() const override { return "sqlite3"; }
  std::vector<std::string> compressions() const override { return {}; }
  const std::vector<RecordingTopic>& topics() const override { return topics_; }
  std::vector<std::string> warnings() const override { return warnings_; }

  Status SetTopicFilter(const std::vector<int>& topics) override {
    filter_ = topics;
    filtered_ = true;
    return Status::Ok();
  }

  Status SetTimeFilter(TimeNs first_ns, TimeNs last_ns) override {
    time_first_ns_ = first_ns;
    time_last_ns_ = last_ns;
    time_filtered_ = true;
    return Status::Ok();
  }

  StatusOr<bool> Next(RawMessage* out) override {
    if (!error_.ok()) return error_;
    if (stmt_ == nullptr) {
      if (Status s = Prepare(); !s.ok()) return error_ = s;
    }
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_DONE) return false;
    if (rc != SQLITE_ROW) return error_ = Error("reading the messages table failed");
    auto it = topic_index_.find(sqlite3_column_int64(stmt_, 0));
    if (it == topic_index_.end())
      return error_ = Status::InvalidInput("db3 '" + path_ + "': a message names topic id " +
                                           std::to_string(sqlite3_column_int64(stmt_, 0)) +
                                           ", which is not in the topics table");
    out->topic = it->second;
    out->stamp_ns = sqlite3_column_int64(stmt_, 1);
    const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, 2));
    const int size = sqlite3_column_bytes(stmt_, 2);
    out->data.assign(blob, blob + (blob == nullptr ? 0 : size));
    return true;
  }

  StatusOr<RecordingTopicStats> Span() override {
    sqlite3_stmt* q = nullptr;
    if (sqlite3_prepare_v2(db_, "SELECT COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages",
                           -1, &q, nullptr) != SQLITE_OK)
      return Error("has no readable messages table");
    RecordingTopicStats span;
    const int rc = sqlite3_step(q);
    if (rc == SQLITE_ROW)
      span = {sqlite3_column_int64(q, 0), sqlite3_column_int64(q, 1), sqlite3_column_int64(q, 2)};
    sqlite3_finalize(q);
    if (rc != SQLITE_ROW) return Error("reading the messages table failed");
    return span;
  }

  StatusOr<std::vector<RecordingTopicStats>> TopicStats() override {
    std::vector<RecordingTopicStats> stats(topics_.size());
    sqlite3_stmt* q = nullptr;
    if (sqlite3_prepare_v2(db_,
                           "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) "
                           "FROM messages GROUP BY topic_id",
                           -1, &q, nullptr) != SQLITE_OK)
      return Error("has no readable messages table");
    int rc;
    while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
      auto it = topic_index_.find(sqlite3_column_int64(q, 0));
      if (it == topic_index_.end()) continue;
      stats[it->second] = {sqlite3_column_int64(q, 1), sqlite3_column_int64(q, 2),
                           sqlite3_column_int64(q, 3)};
    }
    sqlite3_finalize(q);
    if (rc != SQLITE_DONE) return Error("reading the messages table failed");
    return stats;
  }

 private:
  static std::string Text(sqlite3_stmt* q, int col) {
    const unsigned char* t = sqlite3_column_text(q, col);
    return t == nullptr ? std::string() : reinterpret_cast<const char*>(t);
  }

  Status Error(const std::string& what) const {
    const char* why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    return Status::InvalidInput("db3 '" + path_ + "' " + what + " (sqlite: " + why + ")");
  }

  // Ordered by receive time, then insertion: a prepared statement that sqlite
  // steps through (the timestamp index of rosbag2 makes this a scan).
  Status Prepare() {
    std::string sql = "SELECT topic_id, timestamp, data FROM messages";
    if (filtered_) {
      sql += " WHERE topic_id IN (";
      bool first = true;
      for (const auto& [id, index] : topic_index_) {
        if (std::find(filter_.begin(), filter_.end(), index) == filter_.end()) continue;
        sql += (first ? "" : ",") + std::to_string(id);
        first = false;
      }
      sql += ")";
    }
    if (time_filtered_) {
      sql += filtered_ ? " AND" : " WHERE";
      sql += " timestamp BETWEEN " + std::to_string(time_first_ns_) + " AND " +
             std::to_string(time_last_ns_);
    }
    sql += " ORDER BY timestamp, id";
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK)
      return Error("has no readable messages table");
    return Status::Ok();
  }

  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* stmt_ = nullptr;
  std::vector<RecordingTopic> topics_;
  std::vector<std::string> warnings_;
  std::map<int64_t, int> topic_index_;  // topics.id -> index
  std::vector<int> filter_;
  bool filtered_ = false;
  TimeNs time_first_ns_ = 0, time_last_ns_ = 0;
  bool time_filtered_ = false;
  Status error_;
};

// ---------------------------------------------------------------------------
// MCAP

class McapSource final : public RecordingSource {
 public:
  explicit McapSource(std::string path) : path_(std::move(path)) {}

  Status Init() {
    StatusOr<std::unique_ptr<mcap::Reader>> reader = mcap::Reader::Open(path_);
    if (!reader.ok()) return reader.status();
    reader_ = std::move(reader).value();
    for (const auto& [id, channel] : reader_->channels()) {
      auto schema = reader_->schemas().find(channel.schema_id);
      const std::string type = schema == reader_->schemas().end() ? "" : schema->second.name;
      channel_index_[id] = static_cast<int>(topics_.size());
      channel_ids_.push_back(id);
      topics_.push_back({channel.topic, type, channel.message_encoding});
    }
    return Status::Ok();
  }

  const std::string& path() const override { return path_; }
  std::string storage() const override { return "mcap"; }
  std::vector<std::string> compressions() const override {
    std::vector<std::string> out;
    for (const std::string& c : reader_->summary().compressions) out.push_back(c.empty() ? "none" : c);
    return out;
  }
  const std::vector<RecordingTopic>& topics() const override { return topics_; }
  std::vector<std::string> warnings() const override { return reader_->warnings(); }
  bool truncated() const override { return reader_->summary().truncated; }

  Status SetTopicFilter(const std::vector<int>& topics) override {
    std::vector<uint16_t> ids;
    for (int t : topics) {
      if (t >= 0 && t < static_cast<int>(channel_ids_.size())) ids.push_back(channel_ids_[t]);
    }
    reader_->SetChannelFilter(ids);
    return Status::Ok();
  }

  // Receive times before the epoch hold no MCAP message (log times are unsigned).
  Status SetTimeFilter(TimeNs first_ns, TimeNs last_ns) override {
    if (last_ns < 0 || first_ns > last_ns) {
      reader_->SetTimeRange(1, 0);
    } else {
      reader_->SetTimeRange(static_cast<uint64_t>(std::max<TimeNs>(first_ns, 0)),
                            static_cast<uint64_t>(last_ns));
    }
    return Status::Ok();
  }

  StatusOr<bool> Next(RawMessage* out) override {
    while (true) {
      StatusOr<bool> got = reader_->Next(&message_);
      if (!got.ok() || !*got) return got;
      auto it = channel_index_.find(message_.channel_id);
      if (it == channel_index_.end()) continue;  // a channel not known up front: skipped
      out->topic = it->second;
      out->stamp_ns = static_cast<TimeNs>(message_.log_time_ns);
      out->data.swap(message_.data);  // both buffers keep their capacity for reuse
      return true;
    }
  }

  // The summary's statistics (or what the linear scan at open counted).
  StatusOr<RecordingTopicStats> Span() override {
    const mcap::FileSummary& summary = reader_->summary();
    RecordingTopicStats span;
    span.count = static_cast<int64_t>(summary.message_count);
    if (span.count > 0) {
      span.first_ns = static_cast<TimeNs>(summary.message_start_time_ns);
      span.last_ns = static_cast<TimeNs>(summary.message_end_time_ns);
    }
    return span;
  }

  // A second reader over the whole file: counts and spans per channel.
  StatusOr<std::vector<RecordingTopicStats>> TopicStats() override {
    StatusOr<std::unique_ptr<mcap::Reader>> reader = mcap::Reader::Open(path_);
    if (!reader.ok()) return reader.status();
    std::vector<RecordingTopicStats> stats(topics_.size());
    mcap::Message m;
    while (true) {
      StatusOr<bool> got = (*reader)->Next(&m);
      if (!got.ok()) return got.status();
      if (!*got) break;
      auto it = channel_index_.find(m.channel_id);
      if (it == channel_index_.end()) continue;
      RecordingTopicStats& s = stats[it->second];
      const TimeNs t = static_cast<TimeNs>(m.log_time_ns);
      s.first_ns = s.count == 0 ? t : std::min(s.first_ns, t);
      s.last_ns = s.count == 0 ? t : std::max(s.last_ns, t);
      ++s.count;
    }
    return stats;
  }

 private:
  std::string path_;
  std::unique_ptr<mcap::Reader> reader_;
  std::vector<RecordingTopic> topics_;
  std::map<uint16_t, int> channel_index_;
  std::vector<uint16_t> channel_ids_;  // topic index -> channel id
  mcap::Message message_;
};

StatusOr<std::unique_ptr<RecordingSource>> OpenFile(const std::string& path, RecordingKind kind) {
  if (kind == RecordingKind::kSqlite3) {
    auto source = std::make_unique<SqliteSource>(path);
    if (Status s = source->Init(); !s.ok()) return s;
    return std::unique_ptr<RecordingSource>(std::move(source));
  }
  if (kind == RecordingKind::kMcap) {
    auto source = std::make_unique<McapSource>(path);
    if (Status s = source->Init(); !s.ok()) return s;
    return std::unique_ptr<RecordingSource>(std::move(source));
  }
  return Status::InvalidInput("'" + path + "' is a " + RecordingKindName(kind) +
                              " recording, not a ROS 2 storage file");
}

// ---------------------------------------------------------------------------
// Bag folder: metadata.yaml + files, merged by receive time.

struct FolderMetadata {
  std::string storage;
  std::vector<std::string> files;  // absolute or relative to the working directory
};

StatusOr<FolderMetadata> ReadMetadata(const std::string& folder) {
  const std::string file = (fs::path(folder) / kMetadataFile).string();
  YAML::Node info;
  try {
    info = YAML::LoadFile(file)["rosbag2_bagfile_information"];
  } catch (const std::exception& e) {
    return Status::InvalidInput("'" + file + "' is not valid YAML (" + e.what() + ")");
  }
  if (!info || !info.IsMap())
    return Status::InvalidInput("'" + file + "' has no rosbag2_bagfile_information map");
  FolderMetadata m;
  try {
    m.storage = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
    const std::string compression =
        info["compression_format"] ? info["compression_format"].as<std::string>() : "";
    if (!compression.empty())
      return Status::InvalidInput("'" + file + "': compression_format '" + compression +
                                  "' (whole-file compression) is not supported; decompress the "
                                  "bag with `ros2 bag convert` first");
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0)
      return Status::InvalidInput("'" + file + "' lists no relative_file_paths");
    for (const YAML::Node& p : paths) m.files.push_back(p.as<std::string>());
  } catch (const std::exception& e) {
    return Status::InvalidInput("'" + file + "' has a malformed field (" + e.what() + ")");
  }
  if (m.storage != "sqlite3" && m.storage != "mcap")
    return Status::InvalidInput("'" + file + "': storage_identifier '" + m.storage +
                                "' is not supported (sqlite3 or mcap)");
  for (std::string& rel : m.files) {
    // Older rosbag2 versions prefix the folder name; accept both.
    fs::path candidate = fs::path(folder) / rel;
    std::error_code ec;
    if (!fs::exists(candidate, ec) && fs::exists(fs::path(folder).parent_path() / rel, ec))
      candidate = fs::path(folder).parent_path() / rel;
    if (!fs::is_regular_file(candidate, ec))
      return Status::InvalidInput("'" + file + "' names file '" + rel + "', which does not exist");
    rel = candidate.string();
  }
  return m;
}

class FolderSource final : public RecordingSource {
 public:
  explicit FolderSource(std::string path) : path_(std::move(path)) {}

  Status Init() {
    StatusOr<FolderMetadata> meta = ReadMetadata(path_);
    if (!meta.ok()) return meta.status();
    storage_ = meta->storage;
    for (const std::string& file : meta->files) {
      StatusOr<RecordingKind> kind = DetectRecording(file);
      if (!kind.ok()) return kind.status();
      const RecordingKind want =
          storage_ == "mcap" ? RecordingKind::kMcap : RecordingKind::kSqlite3;
      if (*kind != want)
        return Status::InvalidInput("'" + file + "' is a " + RecordingKindName(*kind) +
                                    " file, but metadata.yaml of '" + path_ + "' says " + storage_);
      StatusOr<std::unique_ptr<RecordingSource>> part = OpenFile(file, *kind);
      if (!part.ok()) return part.status();
      AddTopics(**part);
      parts_.push_back(std::move(part).value());
    }
    heads_.resize(parts_.size());
    return Status::Ok();
  }

  const std::string& path() const override { return path_; }
  std::string storage() const override { return storage_; }
  std::vector<std::string> compressions() const override {
    std::vector<std::string> out;
    for (const auto& p : parts_) {
      for (const std::string& c : p->compressions()) {
        if (std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
      }
    }
    return out;
  }
  const std::vector<RecordingTopic>& topics() const override { return topics_; }
  std::vector<std::string> warnings() const override {
    std::vector<std::string> out;
    for (const auto& p : parts_) {
      for (const std::string& w : p->warnings()) out.push_back(w);
    }
    return out;
  }
  bool truncated() const override {
    return std::any_of(parts_.begin(), parts_.end(), [](const auto& p) { return p->truncated(); });
  }

  Status SetTopicFilter(const std::vector<int>& topics) override {
    for (size_t i = 0; i < parts_.size(); ++i) {
      std::vector<int> local;
      for (size_t t = 0; t < to_merged_[i].size(); ++t) {
        if (std::find(topics.begin(), topics.end(), to_merged_[i][t]) != topics.end())
          local.push_back(static_cast<int>(t));
      }
      if (Status s = parts_[i]->SetTopicFilter(local); !s.ok()) return s;
    }
    return Status::Ok();
  }

  Status SetTimeFilter(TimeNs first_ns, TimeNs last_ns) override {
    for (const auto& part : parts_) {
      if (Status s = part->SetTimeFilter(first_ns, last_ns); !s.ok()) return s;
    }
    return Status::Ok();
  }

  // The earliest head of all parts (ties: the earlier file).
  StatusOr<bool> Next(RawMessage* out) override {
    if (!error_.ok()) return error_;
    if (!started_) {
      started_ = true;
      for (size_t i = 0; i < parts_.size(); ++i) {
        if (Status s = Advance(i); !s.ok()) return error_ = s;
      }
    }
    int best = -1;
    for (size_t i = 0; i < heads_.size(); ++i) {
      if (heads_[i].has && (best < 0 || heads_[i].msg.stamp_ns < heads_[best].msg.stamp_ns))
        best = static_cast<int>(i);
    }
    if (best < 0) return false;
    *out = std::move(heads_[best].msg);
    out->topic = to_merged_[best][out->topic];
    if (Status s = Advance(best); !s.ok()) return error_ = s;
    return true;
  }

  StatusOr<RecordingTopicStats> Span() override {
    RecordingTopicStats span;
    for (const auto& part : parts_) {
      StatusOr<RecordingTopicStats> p = part->Span();
      if (!p.ok()) return p.status();
      if (p->count == 0) continue;
      span.first_ns = span.count == 0 ? p->first_ns : std::min(span.first_ns, p->first_ns);
      span.last_ns = span.count == 0 ? p->last_ns : std::max(span.last_ns, p->last_ns);
      span.count += p->count;
    }
    return span;
  }

  StatusOr<std::vector<RecordingTopicStats>> TopicStats() override {
    std::vector<RecordingTopicStats> stats(topics_.size());
    for (size_t i = 0; i < parts_.size(); ++i) {
      StatusOr<std::vector<RecordingTopicStats>> part = parts_[i]->TopicStats();
      if (!part.ok()) return part.status();
      for (size_t t = 0; t < part->size(); ++t) {
        const RecordingTopicStats& p = (*part)[t];
        if (p.count == 0) continue;
        RecordingTopicStats& s = stats[to_merged_[i][t]];
        s.first_ns = s.count == 0 ? p.first_ns : std::min(s.first_ns, p.first_ns);
        s.last_ns = s.count == 0 ? p.last_ns : std::max(s.last_ns, p.last_ns);
        s.count += p.count;
      }
    }
    return stats;
  }

 private:
  struct Head {
    bool has = false;
    RawMessage msg;
  };

  void AddTopics(const RecordingSource& part) {
    std::vector<int> map;
    for (const RecordingTopic& t : part.topics()) {
      auto it = std::find_if(topics_.begin(), topics_.end(),
                             [&](const RecordingTopic& m) { return m.name == t.name; });
      if (it == topics_.end()) {
        map.push_back(static_cast<int>(topics_.size()));
        topics_.push_back(t);
      } else {
        map.push_back(static_cast<int>(it - topics_.begin()));
      }
    }
    to_merged_.push_back(std::move(map));
  }

  Status Advance(size_t i) {
    StatusOr<bool> got = parts_[i]->Next(&heads_[i].msg);
    if (!got.ok()) return got.status();
    heads_[i].has = *got;
    return Status::Ok();
  }

  std::string path_, storage_;
  std::vector<std::unique_ptr<RecordingSource>> parts_;
  std::vector<std::vector<int>> to_merged_;  // part -> its topic index -> merged index
  std::vector<RecordingTopic> topics_;
  std::vector<Head> heads_;
  bool started_ = false;
  Status error_;
};

}  // namespace

const char* RecordingKindName(RecordingKind kind) {
  switch (kind) {
    case RecordingKind::kRos1Bag: return "ros1";
    case RecordingKind::kMcap: return "mcap";
    case RecordingKind::kSqlite3: return "sqlite3";
    case RecordingKind::kRos2Folder: return "ros2 folder";
    case RecordingKind::kPcap: return "pcap";
  }
  return "unknown";
}

StatusOr<RecordingKind> DetectRecording(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return Status::InvalidInput("bag '" + path + "' does not exist");
  if (S_ISDIR(st.st_mode)) return DetectDirectory(path);
  if (!S_ISREG(st.st_mode)) return Status::InvalidInput("'" + path + "' is not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::InvalidInput("cannot read '" + path + "'");
  std::string head(16, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  if (StartsWith(head, kRos1Magic, sizeof(kRos1Magic) - 1)) return RecordingKind::kRos1Bag;
  if (StartsWith(head, kMcapMagic, sizeof(kMcapMagic) - 1)) return RecordingKind::kMcap;
  if (StartsWith(head, kSqliteMagic, sizeof(kSqliteMagic))) return RecordingKind::kSqlite3;
  const auto* bytes = reinterpret_cast<const uint8_t*>(head.data());
  if (IsPcapMagic(bytes, head.size()) || IsPcapngMagic(bytes, head.size()))
    return RecordingKind::kPcap;  // pcapng: the capture reader says why it cannot read it
  // A .bag of no known kind goes to the ROS1 reader, which says why it is not
  // a bag (empty, truncated header, text).
  if (fs::path(path).extension() == ".bag") return RecordingKind::kRos1Bag;
  return Status::InvalidInput("'" + path + "' is not a recording rvlio reads (neither a ROS1 bag, "
                              "an MCAP file, a sqlite3 .db3, a ROS 2 bag folder nor a pcap capture)");
}

StatusOr<std::unique_ptr<RecordingSource>> RecordingSource::Open(const std::string& path) {
  StatusOr<RecordingKind> kind = DetectRecording(path);
  if (!kind.ok()) return kind.status();
  if (*kind == RecordingKind::kRos2Folder) {
    auto source = std::make_unique<FolderSource>(path);
    if (Status s = source->Init(); !s.ok()) return s;
    return std::unique_ptr<RecordingSource>(std::move(source));
  }
  return OpenFile(path, *kind);
}

}  // namespace rvlio
